"""The controller reaches the robot only through measurements and joint targets: it imports
nothing of the simulator, and recorded measurements alone drive it to the same targets."""

import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from footfall.core.files import plain_json
from footfall.features.reward import default_reward
from footfall.sim.episode import Walk, WalkConfig
from maps import short_flat_board

CONTROL = Path(__file__).resolve().parent.parent / "src" / "footfall" / "control"
FORBIDDEN = ("mujoco", "footfall.sim")  # the simulator, and whatever wraps it


def simulator_imports(root: Path) -> list[str]:
    """Every import of the simulator (:data:`FORBIDDEN`) in the modules below ``root``."""
    found = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                     else [node.module] if isinstance(node, ast.ImportFrom) and node.module
                     else [])
            found += [f"{path.relative_to(root)}:{node.lineno} {name}" for name in names
                      if any(name == f or name.startswith(f + ".") for f in FORBIDDEN)]
    return found


def test_no_controller_module_imports_the_simulator():
    assert simulator_imports(CONTROL) == []


def test_the_check_finds_a_simulator_import(tmp_path):
    (tmp_path / "spy.py").write_text("import numpy\nfrom footfall.sim.simulation import Simulation"
                                     "\nif True:\n    import mujoco.viewer\n")
    assert simulator_imports(tmp_path) == ["spy.py:2 footfall.sim.simulation",
                                           "spy.py:4 mujoco.viewer"]


class Recorded(Walk):
    """A walk that keeps every measurement its controller was given and every target it
    answered."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.measured, self.answered = [], []

    def _measure(self):
        m = super()._measure()
        self.measured.append(m)
        return m

    def _actuate(self, targets):
        self.answered.append(targets)
        super()._actuate(targets)


# The replay, in a process where the simulator cannot be imported: a fresh controller, given the
# map, its settings and the recorded measurements, must answer the recorded targets.
REPLAY = """
import importlib.abc, json, sys
from pathlib import Path
from types import SimpleNamespace

class NoSimulator(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split(".")[0] == "mujoco" or name.startswith("footfall.sim"):
            raise ImportError(f"the controller imported {name}")
        return None

sys.meta_path.insert(0, NoSimulator())
import numpy as np
from footfall.control.body_path import BodyPathConfig
from footfall.control.cog import CogConfig
from footfall.control.controller import Controller, footstep_planner
from footfall.control.footstep import FootstepConfig
from footfall.control.lowlevel import LowLevelConfig
from footfall.control.measurements import Measurements
from footfall.control.pose_finder import PoseConfig
from footfall.control.reflexes import ReflexConfig
from footfall.control.swing import SwingConfig
from footfall.core.heightmap import HeightMap
from footfall.core.state import nominal_state
from footfall.core.robot import LITTLEDOG
from footfall.features.reward import default_reward

folder = Path(sys.argv[1])
run = json.loads((folder / "run.json").read_text())
nested = {"footstep": FootstepConfig, "cog": CogConfig, "swing": SwingConfig, "pose": PoseConfig,
          "lowlevel": LowLevelConfig, "reflexes": ReflexConfig, "path": BodyPathConfig}
settings = SimpleNamespace(**{k: nested[k].from_dict(v) if k in nested else v
                              for k, v in run["walk"].items()})
hmap = HeightMap.load(folder / "board.npz")
start, goal = np.array(run["start"]), np.array(run["goal"])
reward = default_reward()
planner = footstep_planner(hmap, lambda leg: reward, start, goal, settings, LITTLEDOG)
rec = np.load(folder / "recorded.npz")
m = [Measurements(float(t), q, p, r, f) for t, q, p, r, f in
     zip(rec["time"], rec["q"], rec["position"], rec["rpy"], rec["forces"])]
state0 = nominal_state(hmap, start, 0.0, LITTLEDOG.gait_order[0], goal=goal, robot=LITTLEDOG)
controller = Controller(hmap, planner, goal, run["goal_x"], settings, LITTLEDOG)
controller.start(m[0], state0.feet)
for i in range(len(rec["target_q"])):
    t = controller.act()
    assert np.array_equal(t.q, rec["target_q"][i]), i
    assert np.array_equal(t.qd, rec["target_qd"][i]), i
    assert np.array_equal(t.torque, rec["target_torque"][i]), i
    controller.sense(m[i + 1])
assert controller.act() is None and controller.stopped == "step limit"
left = sorted(n for n in sys.modules if n.split(".")[0] == "mujoco" or n.startswith("footfall.sim"))
assert not left, left
print(len(rec["target_q"]), "periods replayed")
"""


def test_recorded_measurements_alone_drive_the_controller_to_the_same_targets(tmp_path):
    board = short_flat_board()
    config = WalkConfig(start_setback=0.2, max_steps=3)
    reward = default_reward()
    run = Recorded(board, lambda leg: reward, 4, config)
    record = run.run()
    assert record.result["reason"] == "step limit" and len(run.answered) > 100
    m = run.measured
    np.savez(tmp_path / "recorded.npz", time=[x.time for x in m],
             q=[x.joint_angles for x in m], position=[x.body_position for x in m],
             rpy=[x.body_rpy for x in m], forces=[x.foot_forces for x in m],
             target_q=[t.q for t in run.answered], target_qd=[t.qd for t in run.answered],
             target_torque=[t.torque for t in run.answered])
    board.save(tmp_path / "board.npz")
    (tmp_path / "run.json").write_text(json.dumps({
        "walk": plain_json(config.to_dict(), nonfinite="null"), "start": run.start_xy.tolist(),
        "goal": run.goal.tolist(), "goal_x": run.goal_x}))
    replay = subprocess.run([sys.executable, "-c", REPLAY, str(tmp_path)], capture_output=True,
                            text=True, timeout=300)
    assert replay.returncode == 0, replay.stderr
    assert replay.stdout.strip() == f"{len(run.answered)} periods replayed"
