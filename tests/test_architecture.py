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


# ------------------------------------------------------------------ module and class size
MAX_MODULE_LINES = 500  # STYLE.md: one concept per module
MAX_CLASS_LINES = 300  # a class that grows past this holds more than one part (issue 22)
LARGE_YET = {  # parts larger than that today, each to be split; the list may only shrink
    "control/body_path.py", "control/cog.py", "experiments/bench.py",
    "experiments/reproduce.py", "expert/collect.py", "expert/synthetic.py", "sim/mjcf.py",
    "terrain/modules.py", "terrain/scans.py", "sim/simulation.py:Simulation",
}


def large_parts(root: Path, module_limit: int = MAX_MODULE_LINES,
                class_limit: int = MAX_CLASS_LINES) -> list[str]:
    """Every module below ``root`` longer than ``module_limit`` lines, as ``path``, and every
    class longer than ``class_limit`` lines (from its first decorator), as ``path:Class``."""
    found = []
    for path in sorted(root.rglob("*.py")):
        source = path.read_text(encoding="utf-8")
        name = path.relative_to(root).as_posix()
        if len(source.splitlines()) > module_limit:
            found.append(name)
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.ClassDef):
                first = min([node.lineno] + [d.lineno for d in node.decorator_list])
                if node.end_lineno - first + 1 > class_limit:
                    found.append(f"{name}:{node.name}")
    return found


def test_no_module_over_500_lines_and_no_class_over_300_but_those_being_split():
    found = set(large_parts(SRC))
    assert found - LARGE_YET == set(), "split these (one concept per module, one part per class)"
    assert LARGE_YET - found == set(), "these are small now: take them off LARGE_YET"


def test_the_size_check_names_a_long_module_and_a_long_class(tmp_path):
    (tmp_path / "pkg").mkdir()
    body = "".join(f"    x{i} = {i}\n" for i in range(10))
    (tmp_path / "pkg" / "m.py").write_text(f"class Small:\n{body}\n\nclass Big:\n{body * 3}")
    assert large_parts(tmp_path, module_limit=40, class_limit=20) == ["pkg/m.py", "pkg/m.py:Big"]
    assert large_parts(tmp_path, module_limit=60, class_limit=40) == []
