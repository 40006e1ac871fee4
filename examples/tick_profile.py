"""Where a control period's time goes: a sampling profile of warm rocky runs, as a table.

``footfall bench sim`` splits a run into set-up, planning, physics and "the
control periods around the physics" by timers. This script splits the last
part further, by function, with a sampling profiler (py-spy). It walks the benchmark's board
(flat | rocky 0.5 | flat, seed 0) once to warm the process (imports, compiled
kernels, the board's reward grids), then ``RUNS`` timed hand-tuned runs
(seeds 1, 2, ...), and prints the microseconds per 100 Hz control period of
each part of those runs.

Run::

    pip install py-spy
    python examples/tick_profile.py out.json
    py-spy record -r 400 -f raw -o stacks.txt -- python examples/tick_profile.py profiled.json
    python examples/tick_profile.py --table stacks.txt out.json

The first walk, without the profiler, measures the timed runs' CPU seconds
and control periods (``out.json``); the second, under py-spy, gives each
part's share of them. py-spy pauses the process at each sample (its
non-blocking mode tears the stacks of short calls): that costs the profiled
walk about a third more CPU, spread over whatever was running, so the shares
hold and the microseconds come from the walk without the profiler.
"""

from __future__ import annotations

import json
import re
import sys
import time
from collections import Counter

RUNS = 3  # timed runs (seeds 1..RUNS) after the warm-up run (seed 0)
TIMED = "timed_runs"  # the function whose samples count (the warm-up's do not)

# The table's rows: a label and the profiled frames (function (file)) whose inclusive samples
# it counts, in the order a control period calls them. A frame counts once per sample.
PARTS = [
    ("physics: MuJoCo's step", ["Simulation._step (simulation.py)"]),
    ("planning: footsteps", ["Controller._plan (controller.py)"]),
    ("planning: pose finder, COG plan", ["Controller.body_motion (controller.py)"]),
    ("sensors: joint angles, trunk pose, foot forces", ["Walk._measure (episode.py)"]),
    ("estimate: body points and rotation", ["BodyEstimate.__init__ (estimate.py)"]),
    ("stance watch: slip and tilt", ["Controller._watch (controller.py)"]),
    ("load control: shares", ["load_shares (load.py)"]),
    ("load control: offsets, hold, pressing",
     ["load_offsets (load.py)", "load_held (load.py)", "pressed (load.py)"]),
    ("support torques (Jacobians)",
     ["BodyEstimate.jacobians (estimate.py)", "support_torques (load.py)"]),
    ("inverse kinematics", ["joint_targets (lowlevel.py)"]),
    ("rolling feet (shin rotations)", ["rolled (lowlevel.py)", "shin_rotations (lowlevel.py)"]),
    ("body correction, transfer ramps",
     ["BodyCorrection.update (lowlevel.py)", "transfer_weight (lowlevel.py)",
      "body_rotation (lowlevel.py)"]),
    ("task: contacts, progress, flight recorder", ["WalkTask.judge (task.py)"]),
    ("servo set-points to MuJoCo", ["Walk._actuate (episode.py)"]),
    ("phases: lift-off, touch-down, gate", ["Controller.lift_off (controller.py)",
                                            "Controller.touching_down (controller.py)",
                                            "LiftOffGate.wait (gate.py)"]),
]


def walk(out_json: str) -> None:
    """The warm-up run, then the timed ones; their CPU and control periods to ``out_json``."""
    from footfall.experiments.bench.sim import default_reward
    from footfall.sim.episode import Walk
    from footfall.terrain import make_board

    board = make_board([("rocky", 0.5)], seed=0)
    reward = default_reward()
    Walk(board, lambda leg: reward, 0).run()
    with open(out_json, "w") as f:
        json.dump({**timed_runs(Walk, board, reward), "runs": RUNS}, f)


def timed_runs(walk_class, board, reward) -> dict:
    """CPU [s] of the timed runs, and of their physics; control periods; simulated time [s]."""
    cpu, physics, periods, simulated = time.process_time(), 0.0, 0, 0.0
    for seed in range(1, RUNS + 1):
        run = walk_class(board, lambda leg: reward, seed)
        record = run.run()
        physics += run.sim.physics_cpu
        periods += int(round(record.result["time"] / run.config.lowlevel.period))
        simulated += float(record.result["time"])
    return {"cpu_s": time.process_time() - cpu, "physics_cpu_s": physics,
            "control_periods": periods, "simulated_s": simulated}


def table(stacks: str, out_json: str) -> str:
    """The markdown table of microseconds per control period, from py-spy's raw stacks."""
    totals = json.load(open(out_json))
    inclusive: Counter = Counter()
    timed = 0
    for line in open(stacks):
        stack, count = line.rsplit(" ", 1)
        names = []
        for frame in stack.split(";"):
            m = re.match(r"(.*?) \((.*?):\d+\)", frame)
            names.append(f"{m.group(1)} ({m.group(2).rsplit('/', 1)[-1]})" if m else frame)
        if not any(n.startswith(TIMED + " ") for n in names):
            continue
        timed += int(count)
        for part, frames in PARTS:
            if any(n in frames for n in names):
                inclusive[part] += int(count)
    us = 1e6 * totals["cpu_s"] / totals["control_periods"]  # [us] CPU per control period
    rows = ["| part of a 10 ms control period | us | share |", "| --- | --- | --- |"]
    counted = 0
    for part, _ in PARTS:
        share = inclusive[part] / timed
        counted += inclusive[part]
        rows.append(f"| {part} | {us * share:.0f} | {100 * share:.0f} % |")
    rest = 1 - counted / timed
    rows.append(f"| the rest (the loop, generators, notes) | {us * rest:.0f} | {100 * rest:.0f} % |")
    rows.append(f"| **whole period** | **{us:.0f}** | real time x{totals['simulated_s'] / totals['cpu_s']:.1f} |")
    return "\n".join(rows)


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--table":
        print(table(sys.argv[2], sys.argv[3]))
    else:
        walk(sys.argv[1] if len(sys.argv) > 1 else "tick_profile.json")
