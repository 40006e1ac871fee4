"""The tree is the architecture: each layer imports only from the layers below it."""

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parent.parent / "src" / "footfall"

# The pipeline, lowest layer first (docs/architecture.md). A package may import from packages of
# a lower rank and from itself; packages of the same rank are independent of each other.
LAYERS = {
    "core": 0,         # height map, robot, state, kinematics, errors, files, seeds, statistics
    "terrain": 1,      # terrain generators and scan import
    "features": 2,     # candidates, patches, feature families, the reward, dense scoring
    "data": 2,         # the demonstration store and run logs
    "learning": 3,     # pairwise data, rank learners, training, model files, evaluation
    "expert": 3,       # the synthetic expert, its corrections, the demonstration walker
    "control": 3,      # the control stack: body path, footsteps, pose, COG, swing, low level
    "sim": 4,          # the MuJoCo robot and a walking episode
    "plots": 5,        # pictures
    "experiments": 6,  # offline experiment, reproduction, report, batches of runs, benchmarks
    "teach": 6,        # the teaching interface: people label run steps in the browser
    "cli": 7,          # the command line
}


def _imported_modules(path: Path) -> list[tuple[int, str]]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.append((node.lineno, node.module))
        elif isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
    return [(line, m) for line, m in out if m == "footfall" or m.startswith("footfall.")]


def layer_violations(root: Path, layers: dict[str, int] = LAYERS) -> list[str]:
    """Every import in the package at ``root`` that goes from a layer to the same or a higher one.

    Also reports a top-level package that is not in ``layers`` (every part has a place).
    """
    problems = []
    for path in sorted(root.rglob("*.py")):
        parts = path.relative_to(root).parts
        if len(parts) == 1:
            continue  # the package's own __init__ (version, environment defaults)
        here = parts[0]
        if here not in layers:
            problems.append(f"{path.relative_to(root)}: package {here!r} has no layer")
            continue
        for line, module in _imported_modules(path):
            there = module.split(".")[1] if "." in module else None
            if there is None or there == here:
                continue
            if there not in layers:
                problems.append(f"{path.relative_to(root)}:{line}: imports {module}, which has no layer")
            elif layers[there] >= layers[here]:
                problems.append(f"{path.relative_to(root)}:{line}: {here} (layer {layers[here]}) "
                                f"imports {module} (layer {layers[there]})")
    return problems


def test_every_layer_imports_only_from_lower_layers():
    assert layer_violations(SRC) == []


def test_the_layering_check_catches_an_upward_import(tmp_path):
    # A copy of two packages' worth of tree: features importing control is an upward import.
    for pkg in ("features", "control"):
        (tmp_path / pkg).mkdir()
        (tmp_path / pkg / "__init__.py").write_text("")
    (tmp_path / "control" / "planner.py").write_text("from footfall.features.reward import R\n")
    (tmp_path / "features" / "reward.py").write_text(
        "import numpy\nfrom footfall.control.planner import plan\n")
    found = layer_violations(tmp_path)
    assert found == ["features/reward.py:2: features (layer 2) imports "
                     "footfall.control.planner (layer 3)"]
    # Packages of the same rank may not import each other either.
    (tmp_path / "features" / "reward.py").write_text("from footfall.data.store import S\n")
    (tmp_path / "data").mkdir()
    assert layer_violations(tmp_path) == ["features/reward.py:1: features (layer 2) imports "
                                          "footfall.data.store (layer 2)"]


def test_the_top_level_holds_a_handful_of_entries():
    entries = sorted(p.name for p in SRC.iterdir() if p.name != "__pycache__")
    assert len(entries) <= 13, entries  # __init__.py and one package per role (12 roles)
    assert set(LAYERS) <= set(entries)


# ------------------------------------------------------------------ function length
MAX_FUNCTION_LINES = 80  # STYLE.md: small phases, not long methods (issue 16)
LONG_MARKER = "# long:"  # "# long: <why>" at a function's top lets it be longer


def long_functions(root: Path, limit: int = MAX_FUNCTION_LINES) -> list[str]:
    """Every function or method below ``root`` longer than ``limit`` lines without a reason.

    A function's lines run from its first decorator (or ``def``) to its last line, docstring
    included. A comment ``# long: <why>`` on the line above it or at its top (before the first
    statement after the docstring) is its reason. Each entry reads ``path:line name (n lines)``.
    """
    found = []
    for path in sorted(root.rglob("*.py")):
        source = path.read_text(encoding="utf-8")
        lines = source.splitlines()
        functions = [node for node in ast.walk(ast.parse(source))
                     if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]
        for node in sorted(functions, key=lambda node: node.lineno):
            first = min([node.lineno] + [d.lineno for d in node.decorator_list])
            length = node.end_lineno - first + 1
            if length <= limit:
                continue
            documented = ast.get_docstring(node) is not None and len(node.body) > 1
            top = lines[max(first - 2, 0):node.body[1 if documented else 0].lineno]
            if any(line.strip().startswith(LONG_MARKER) and line.strip()[len(LONG_MARKER):].strip()
                   for line in top):
                continue
            found.append(f"{path.relative_to(root).as_posix()}:{node.lineno} {node.name} "
                         f"({length} lines)")
    return found


def test_no_function_is_longer_than_80_lines_without_saying_why():
    found = long_functions(SRC)
    assert found == [], ("functions over 80 lines without a '# long: <why>' comment at "
                         "their top:\n" + "\n".join(found))


def test_the_length_check_names_a_long_function_and_accepts_a_reason(tmp_path):
    body = "".join(f"    x{i} = {i}\n" for i in range(80))
    indented = body.replace("    x", "        x")
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "m.py").write_text(
        "def short():\n    return 1\n\n\n"
        f'def long():\n    """Doc."""\n{body}\n\n'
        f'def told():\n    """Doc."""\n    # long: eighty cases read best side by side\n{body}\n\n'
        f"class C:\n    @staticmethod\n    def method():\n{indented}\n\n"
        f"def bare():\n    # long:\n{body}")
    assert long_functions(tmp_path) == ["pkg/m.py:5 long (82 lines)",
                                        "pkg/m.py:176 method (82 lines)",
                                        "pkg/m.py:259 bare (82 lines)"]
    assert long_functions(tmp_path, limit=82) == []


# ------------------------------------------------------------------ class and module length
MAX_CLASS_LINES = 300  # a class this long holds more than one concept
MAX_MODULE_LINES = 500  # a module this long holds more than one concept (STYLE.md: one per file)


def _reason_among(lines: list[str]) -> bool:
    """Whether ``lines`` hold a ``# long: <why>`` comment with a reason after the colon."""
    return any(line.strip().startswith(LONG_MARKER) and line.strip()[len(LONG_MARKER):].strip()
               for line in lines)


def long_classes(root: Path, limit: int = MAX_CLASS_LINES) -> list[str]:
    """Every class below ``root`` longer than ``limit`` lines without a reason.

    Counted and excused as functions are (:func:`long_functions`): from the first decorator to
    the last line, a ``# long: <why>`` on the line above the class or at its top. Each entry
    reads ``path:line name (n lines)``.
    """
    found = []
    for path in sorted(root.rglob("*.py")):
        source = path.read_text(encoding="utf-8")
        lines = source.splitlines()
        classes = [node for node in ast.walk(ast.parse(source)) if isinstance(node, ast.ClassDef)]
        for node in sorted(classes, key=lambda node: node.lineno):
            first = min([node.lineno] + [d.lineno for d in node.decorator_list])
            length = node.end_lineno - first + 1
            if length <= limit:
                continue
            documented = ast.get_docstring(node) is not None and len(node.body) > 1
            if _reason_among(lines[max(first - 2, 0):node.body[1 if documented else 0].lineno]):
                continue
            found.append(f"{path.relative_to(root).as_posix()}:{node.lineno} {node.name} "
                         f"({length} lines)")
    return found


def long_modules(root: Path, limit: int = MAX_MODULE_LINES) -> list[str]:
    """Every module below ``root`` longer than ``limit`` lines without a reason.

    The reason is a ``# long: <why>`` comment at the module's top: between its docstring (or
    its start) and its first statement. Each entry reads ``path (n lines)``.
    """
    found = []
    for path in sorted(root.rglob("*.py")):
        source = path.read_text(encoding="utf-8")
        lines = source.splitlines()
        if len(lines) <= limit:
            continue
        body = ast.parse(source).body
        documented = ast.get_docstring(ast.parse(source)) is not None
        start = body[0].end_lineno if documented else 0
        rest = body[1:] if documented else body
        end = rest[0].lineno - 1 if rest else len(lines)
        if _reason_among(lines[start:end]):
            continue
        found.append(f"{path.relative_to(root).as_posix()} ({len(lines)} lines)")
    return found


def test_no_class_is_longer_than_300_lines_without_saying_why():
    found = long_classes(SRC)
    assert found == [], ("classes over 300 lines without a '# long: <why>' comment at their "
                         "top:\n" + "\n".join(found))


def test_no_module_is_longer_than_500_lines_without_saying_why():
    found = long_modules(SRC)
    assert found == [], ("modules over 500 lines without a '# long: <why>' comment after "
                         "their docstring:\n" + "\n".join(found))


def test_the_class_length_check_names_a_long_class_and_accepts_a_reason(tmp_path):
    body = "".join(f"    x{i} = {i}\n" for i in range(300))
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "m.py").write_text(
        "class Short:\n    x = 1\n\n\n"
        f'class Long:\n    """Doc."""\n{body}\n\n'
        f'class Told:\n    """Doc."""\n    # long: three hundred fields read best side by side\n'
        f"{body}\n\n"
        f"# long: a table of three hundred rows\nclass Above:\n{body}\n\n"
        f"@dataclass\nclass Bare:\n    # long:\n{body}")
    assert long_classes(tmp_path) == ["pkg/m.py:5 Long (302 lines)",
                                      "pkg/m.py:919 Bare (303 lines)"]
    assert long_classes(tmp_path, limit=303) == []


def test_the_module_length_check_names_a_long_module_and_accepts_a_reason(tmp_path):
    body = "".join(f"x{i} = {i}\n" for i in range(500))
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "short.py").write_text('"""Doc."""\n\nx = 1\n')
    (tmp_path / "pkg" / "long.py").write_text(f'"""Doc."""\n\n{body}')
    (tmp_path / "pkg" / "told.py").write_text(
        f'"""Doc."""\n\n# long: five hundred constants read best in one table\n\n{body}')
    (tmp_path / "pkg" / "undocumented.py").write_text(f"# long: generated\n{body}")
    (tmp_path / "pkg" / "late.py").write_text(f'"""Doc."""\n\n{body}# long: too late\n')
    (tmp_path / "pkg" / "bare.py").write_text(f'"""Doc."""\n# long:\n{body}')
    assert long_modules(tmp_path) == ["pkg/bare.py (502 lines)", "pkg/late.py (503 lines)",
                                      "pkg/long.py (502 lines)"]
    assert long_modules(tmp_path, limit=503) == []


# ------------------------------------------------------------------ import cycles
def _module_name(root: Path, path: Path) -> str:
    """``footfall.a.b`` of the file ``root/a/b.py`` (``footfall.a`` of ``root/a/__init__.py``)."""
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(["footfall", *parts])


def _type_checking_only(node: ast.AST, parents: dict) -> bool:
    """Whether ``node`` sits under ``if TYPE_CHECKING:`` (code a type checker reads, never run)."""
    while node in parents:
        node = parents[node]
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            return True
    return False


def _in_function(node: ast.AST, parents: dict) -> bool:
    while node in parents:
        node = parents[node]
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            return True
    return False


def _imports(root: Path) -> list[tuple[str, int, str, bool]]:
    """Every import run below ``root``: (module, line, imported name, inside a function).

    The imported name is dotted in full: ``import a.b`` gives ``a.b``, ``from a.b import c``
    gives ``a.b.c`` (relative imports resolved). Imports under ``if TYPE_CHECKING:`` are left out.
    """
    out = []
    for path in sorted(root.rglob("*.py")):
        module = _module_name(root, path)
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        tree = ast.parse(path.read_text(encoding="utf-8"))
        parents = {child: node for node in ast.walk(tree) for child in ast.iter_child_nodes(node)}
        for node in ast.walk(tree):
            if not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            if _type_checking_only(node, parents):
                continue
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            else:
                base = node.module or ""
                if node.level:
                    up = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join(up + ([base] if base else []))
                names = [f"{base}.{alias.name}" for alias in node.names]
            out += [(module, node.lineno, name, _in_function(node, parents)) for name in names]
    return out


def import_graph(root: Path) -> dict[str, set[str]]:
    """Module -> the footfall modules it imports, at module level or inside functions.

    ``from a.b import c`` is an edge to the module ``a.b.c`` if there is one, else to ``a.b``;
    the packages above an imported module (whose ``__init__`` Python runs first) are not edges:
    a package's ``__init__`` that imports its own modules is no cycle.
    """
    modules = {_module_name(root, path) for path in root.rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for module, _, name, _ in _imports(root):
        target = name if name in modules else name.rpartition(".")[0]
        if target in modules and target != module:
            graph[module].add(target)
    return graph


def import_cycles(root: Path) -> list[list[str]]:
    """The groups of modules below ``root`` that import each other, directly or around a circle.

    Each group (a strongly connected component of :func:`import_graph` with more than one
    module) is sorted; the groups are sorted by their first module.
    """
    graph = import_graph(root)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    groups = []

    def visit(v: str) -> None:  # Tarjan's algorithm; the graph is a few hundred modules deep at most
        index[v] = low[v] = len(index)
        stack.append(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while not group or group[-1] != v:
                group.append(stack.pop())
            if len(group) > 1:
                groups.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(groups)


def test_no_modules_import_each_other():
    cycles = import_cycles(SRC)
    assert cycles == [], "modules that import each other:\n" + "\n".join(map(str, cycles))


def test_the_cycle_check_catches_a_planted_cycle(tmp_path):
    (tmp_path / "experiments").mkdir()
    (tmp_path / "experiments" / "__init__.py").write_text(
        "from footfall.experiments import runs\n")  # a package importing its own module: no cycle
    (tmp_path / "experiments" / "runs.py").write_text("from footfall.experiments.batch import x\n")
    (tmp_path / "experiments" / "batch.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "from footfall.experiments.executors import Executor\n"
        "if TYPE_CHECKING:\n    from footfall.experiments.runs import RunJob\n")
    (tmp_path / "experiments" / "executors.py").write_text("import footfall.core.files\n")
    assert import_cycles(tmp_path) == []  # the way back to runs is for the type checker only
    (tmp_path / "experiments" / "executors.py").write_text(
        "def execute(job):\n    from footfall.experiments.runs import run\n    return run(job)\n")
    assert import_cycles(tmp_path) == [["footfall.experiments.batch",
                                        "footfall.experiments.executors",
                                        "footfall.experiments.runs"]]
    (tmp_path / "experiments" / "executors.py").write_text("from . import runs\n")
    assert import_cycles(tmp_path) == [["footfall.experiments.batch",
                                        "footfall.experiments.executors",
                                        "footfall.experiments.runs"]]


# ------------------------------------------------------------------ imports inside functions
# Every import sits at its module's top, but for these (module, imported name): a heavy or
# optional dependency that only one path of the program needs.
LAZY_IMPORTS = {
    ("footfall.experiments.executors", "ray"):
        "Ray: an optional extra (footfall[ray]), and heavy; only the ray executor connects",
    ("footfall.experiments.batch", "matplotlib.pyplot"):
        "pyplot picks its backend when imported: only after matplotlib.use('Agg')",
    ("footfall.plots.explain", "matplotlib.pyplot"):
        "pyplot picks its backend when imported: only after matplotlib.use('Agg')",
    ("footfall.experiments.batch", "imageio.v2"):
        "imageio and its bundled ffmpeg: only for a video (footfall walk --video)",
    ("footfall.teach.server", "uvicorn"): "the server itself: only `footfall teach` serves",
    ("footfall.teach.browser", "playwright"):
        "Playwright, a test extra: only the browser tests and `footfall bench teach` drive it",
    ("footfall.teach.bench", "playwright.sync_api"):
        "Playwright, a test extra: only `footfall bench teach` drives the page",
    ("footfall.core.stats", "scipy.stats"):
        "about a second to import: only the exact McNemar test asks for it",
    ("footfall.learning.boosted", "lightgbm"):
        "a second to import: only the boosted learner's training needs it (its model file "
        "holds arrays, scored without LightGBM)",
    ("footfall.learning.veto", "lightgbm"):
        "a second to import: only learning a veto needs it (its trees are arrays in the model)",
    ("footfall.terrain.scans", "footfall.terrain.bags"):
        "rosbags: a fifth of a second to import; only a ROS 2 bag's reader needs it",
    ("footfall.terrain.scans", "footfall.terrain.lidar"):
        "laspy and rasterio: most of a second to import; only a LAS / LAZ reader needs them",
    ("footfall.terrain.scans", "footfall.terrain.geotiff"):
        "rasterio: a third of a second to import; only a GeoTIFF reader needs it",
    ("footfall.terrain.layer_files", "footfall.terrain.bags"):
        "rosbags: only a layer written as a ROS 2 bag needs it",
    ("footfall.terrain.layer_files", "footfall.terrain.geotiff"):
        "rasterio: only a layer written as a GeoTIFF needs it",
    ("footfall.cli.bench", "footfall.cli.fuzz.campaign"):
        "the fuzz suite is built on Hypothesis, a test extra: only `footfall bench fuzz`",
}

def function_level_imports(root: Path) -> list[tuple[str, str, int]]:
    """Every import inside a function below ``root``: (module, imported name, line).

    Imports under ``if TYPE_CHECKING:`` are left out; names as :func:`_imports` gives them.
    """
    return [(module, name, line) for module, line, name, inside in _imports(root) if inside]


def unlisted_lazy_imports(root: Path, allowed=LAZY_IMPORTS) -> list[str]:
    """The function-level imports below ``root`` that ``allowed`` does not name, as
    ``module:line name``; an allowed name covers what is imported from it (``a.b`` covers
    ``a.b.c``)."""
    return [f"{module}:{line} {name}" for module, name, line in function_level_imports(root)
            if not any(module == m and (name == n or name.startswith(n + "."))
                       for m, n in allowed)]


def test_only_heavy_optional_dependencies_are_imported_inside_functions():
    found = unlisted_lazy_imports(SRC)
    assert found == [], ("imports inside functions (move them to the module's top, or add "
                         "them to LAZY_IMPORTS with the reason):\n" + "\n".join(found))
    used = {(m, n) for m, n in LAZY_IMPORTS
            if any(module == m and (name == n or name.startswith(n + "."))
                   for module, name, _ in function_level_imports(SRC))}
    assert used == set(LAZY_IMPORTS)  # the list names no import that has gone


def test_the_lazy_import_check_names_an_unlisted_import_and_accepts_a_listed_one(tmp_path):
    (tmp_path / "plots").mkdir()
    (tmp_path / "plots" / "maps.py").write_text(
        "import numpy\n\n\n"
        "def draw():\n    import matplotlib.pyplot as plt\n    from footfall.core import files\n"
        "    return plt, files\n\n\n"
        "def typed():\n    from typing import TYPE_CHECKING\n    if TYPE_CHECKING:\n"
        "        from footfall.core.heightmap import HeightMap\n")
    found = unlisted_lazy_imports(tmp_path, allowed={})
    assert found == ["footfall.plots.maps:5 matplotlib.pyplot",
                     "footfall.plots.maps:6 footfall.core.files",
                     "footfall.plots.maps:11 typing.TYPE_CHECKING"]
    assert unlisted_lazy_imports(tmp_path, allowed={("footfall.plots.maps", "matplotlib"): "",
                                                    ("footfall.plots.maps", "footfall.core"): "",
                                                    ("footfall.plots.maps", "typing"): ""}) == []
