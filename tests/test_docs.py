"""The documentation stays in step with the code."""

from pathlib import Path

from footfall.core.params import markdown_table, refresh_tables
from footfall.features.pose_features import POSE_FEATURE_NAMES
from footfall.features.terrain_features import QUANTITIES
from test_params import CONFIGS

DOCS = Path(__file__).resolve().parent.parent / "docs"


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
    import re

    texts = [DOCS.parent / "README.md", *sorted(DOCS.glob("*.md"))]
    missing = []
    for path in texts:
        for match in re.finditer(r'(?<!["\w.])footfall(?:\.[A-Za-z_]\w*)+',
                                 path.read_text(encoding="utf-8")):
            if not _resolves(match.group(0).rstrip(".")):
                missing.append(f"{path.name}: {match.group(0)}")
    assert missing == []
