"""The documentation stays in step with the code."""

import re
from pathlib import Path

from footfall.core.params import markdown_table, refresh_tables
from footfall.features.pose_features import POSE_FEATURE_NAMES
from footfall.features.terrain_features import QUANTITIES
from test_params import CONFIGS

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
README = ROOT / "README.md"
README_MAX_LINES = 250  # the README is a front door; results and notes live in docs/


def _pages() -> list[Path]:
    """The README and every Markdown page under docs/ (reports included)."""
    return [README, *sorted(DOCS.rglob("*.md"))]


def test_feature_docs_name_every_feature():
    text = (DOCS / "features.md").read_text()
    for name in POSE_FEATURE_NAMES:
        assert f"`{name}`" in text, name
    for q in QUANTITIES:
        assert f"SCALE.{q}" in text, q


def test_module_previews_exist():
    assert (DOCS / "modules.png").read_bytes()[:4] == b"\x89PNG"


def test_configuration_tables_are_up_to_date():
    """Run ``python -m footfall.core.params docs/configuration.md`` when this fails."""
    text = (DOCS / "configuration.md").read_text()
    assert refresh_tables(text) == text


def test_configuration_docs_have_a_table_and_reasons_for_every_config():
    text = (DOCS / "configuration.md").read_text()
    for cls in CONFIGS:
        marker = f"<!-- params {cls.__module__}.{cls.__qualname__} -->\n"
        assert marker + markdown_table(cls) in text, cls.__name__
        section = text.split(marker)[1].split("\n## ")[0]
        assert "### Why these values" in section, cls.__name__


def _resolves(dotted: str) -> bool:
    """Whether ``footfall.a.b.c`` names an importable module or an attribute of one."""
    import importlib

    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        try:
            for name in parts[k:]:
                obj = getattr(obj, name)
        except AttributeError:
            return False
        return True
    return False


def test_every_module_the_docs_name_exists():
    """``footfall.x.y`` in the README and docs/ names a module or an attribute of one (entry-point
    group names, in quotes, aside), so that the docs follow the code when it moves."""
    missing = []
    for path in [*_pages(), ROOT / "CHANGELOG.md"]:
        for match in re.finditer(r'(?<!["\w.])footfall(?:\.[A-Za-z_]\w*)+',
                                 path.read_text(encoding="utf-8")):
            if not _resolves(match.group(0).rstrip(".")):
                missing.append(f"{path.name}: {match.group(0)}")
    assert missing == []


# A path to a Python file, e.g. ``tests/test_load.py``, ``examples/unseen_terrain.py`` or a glob
# such as ``tests/test_teach_*.py``; not part of a longer path or a URL.
_PY_PATH = re.compile(r"(?<![\w/.:-])((?:[\w.*-]+/)+[\w*-]+\.py)\b")


def _py_path_exists(mention: str, page: Path) -> bool:
    """Whether a ``x/y.py`` mention names a file (or, with ``*``, some file) of the repository:
    from its root, from ``src/`` or ``src/footfall/``, or from the page's own folder."""
    for base in (ROOT, ROOT / "src", ROOT / "src" / "footfall", page.parent):
        if "*" in mention:
            if any(base.glob(mention)):
                return True
        elif (base / mention).is_file():
            return True
    return False


def test_every_file_the_docs_name_exists():
    """``tests/test_x.py`` and the like in the README and docs/ name files that exist."""
    missing = [f"{page.relative_to(ROOT)}: {m.group(1)}"
               for page in [*_pages(), ROOT / "CHANGELOG.md"]
               for m in _PY_PATH.finditer(page.read_text(encoding="utf-8"))
               if not _py_path_exists(m.group(1), page)]
    assert missing == []


def test_python_path_mentions_are_found():
    """The pattern above finds what the docs write, and nothing inside a URL."""
    text = ("`tests/test_load.py`, [x](../examples/unseen_terrain.py), `tests/test_teach_*.py` "
            "https://example.org/a/b.py")
    assert [m.group(1) for m in _PY_PATH.finditer(text)] == [
        "tests/test_load.py", "../examples/unseen_terrain.py", "tests/test_teach_*.py"]


_FENCE = re.compile(r"^(```|~~~).*?^\1[^\n]*$", re.MULTILINE | re.DOTALL)
_INLINE_CODE = re.compile(r"`[^`\n]*`")
_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$", re.MULTILINE)


def _prose(text: str) -> str:
    """The text without fenced code blocks: a ``# comment`` in a shell block is no heading."""
    return _FENCE.sub("", text)


def _slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link: its text
    text = re.sub(r"[^\w\- ]", "", text.lower().replace("`", ""))
    return text.replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    """The anchors a page's headings define, with GitHub's -1, -2 ... for repeated headings."""
    seen: dict[str, int] = {}
    anchors = set()
    for match in _HEADING.finditer(_prose(page.read_text(encoding="utf-8"))):
        slug = _slug(match.group(2))
        anchors.add(slug if slug not in seen else f"{slug}-{seen[slug]}")
        seen[slug] = seen.get(slug, 0) + 1
    return anchors


def _links(page: Path) -> list[str]:
    """Every link and image target of a page, outside code."""
    return [m.group(1) for m in _LINK.finditer(_INLINE_CODE.sub("", _prose(
        page.read_text(encoding="utf-8"))))]


def test_every_link_and_image_resolves():
    """Every relative link and image in the README, CHANGELOG.md and docs/ points at a file that
    exists, and every ``#anchor`` at a heading of its page."""
    broken = []
    for page in [*_pages(), ROOT / "CHANGELOG.md"]:
        for target in _links(page):
            if re.match(r"[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto: ...
                continue
            path, _, anchor = target.partition("#")
            file = (page.parent / path).resolve() if path else page
            if not file.exists():
                broken.append(f"{page.relative_to(ROOT)}: {target} (no such file)")
            elif anchor and file.suffix == ".md" and anchor not in _anchors(file):
                broken.append(f"{page.relative_to(ROOT)}: {target} (no such heading)")
    assert broken == []


def test_link_checks_see_what_github_sees():
    """The slugs and links the checks above rely on, on hand-made cases."""
    assert _slug("Limits: the largest inputs footfall accepts (`footfall.core.limits`)") == (
        "limits-the-largest-inputs-footfall-accepts-footfallcorelimits")
    assert _slug("The lift-off gate's margin") == "the-lift-off-gates-margin"
    text = ("[a](x.md#b) ![c](d.png) `[e](f.md)`\n```\n[g](h.md)\n# not a heading\n```\n"
            "[i [j]](k.md) [l](https://m.org)")
    assert [m.group(1) for m in _LINK.finditer(_INLINE_CODE.sub("", _prose(text)))] == [
        "x.md#b", "d.png", "k.md", "https://m.org"]
    assert not _HEADING.search(_prose(text))


def test_readme_is_a_front_door():
    """The README opens with the two commands and stays short: the rest lives in docs/."""
    text = README.read_text(encoding="utf-8")
    lines = text.splitlines()
    assert len(lines) <= README_MAX_LINES, f"README.md has {len(lines)} lines"
    first_block = _FENCE.search(text).group(0)
    commands = [line.split("#")[0].strip() for line in first_block.splitlines()[1:-1]]
    assert commands == ["make run", "make test"]
    assert text.index(first_block) < text.index("\n## ")  # before any section


# "session 7", "sessions 1-6", "issue 18's", "(issues 5 and 20)": the order in which the work was
# done, which belongs in CHANGELOG.md, not on pages about the project as it is.
_WORK_ORDER = re.compile(r"\b(?:sessions?|issues?)\s+\d+", re.IGNORECASE)


def test_docs_speak_of_the_project_as_it_is():
    """No "session N" and no "issue N" in the README or docs/ (CHANGELOG.md keeps them)."""
    found = [f"{page.relative_to(ROOT)}: {m.group(0)}"
             for page in _pages()
             for m in _WORK_ORDER.finditer(page.read_text(encoding="utf-8"))]
    assert found == []
    assert _WORK_ORDER.findall("Session 7: the gate (issue 18); issues 5 and 20") == [
        "Session 7", "issue 18", "issues 5"]
