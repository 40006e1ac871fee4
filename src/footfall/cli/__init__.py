"""The ``footfall`` command line.

Every command has ``--help`` and ``--json``. A user error (a bad file, a bad
argument) prints one line on standard error and exits with status 2; a
traceback only with ``--debug``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

import click

from footfall.core.errors import FootfallError

EXIT_USER_ERROR = 2


def _emit(as_json: bool, data: dict[str, Any], text: str) -> None:
    if as_json:
        click.echo(json.dumps(data, indent=2, allow_nan=False))
    else:
        click.echo(text)


def _out_path(path: str) -> Path:
    p = Path(path)
    if p.exists() and p.is_dir():
        raise FootfallError(f"output path is a directory: {p}")
    if not p.parent.exists():
        raise FootfallError(f"output directory does not exist: {p.parent}")
    return p


json_option = click.option("--json", "as_json", is_flag=True, help="Print machine-readable JSON.")


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.option("--debug", is_flag=True, help="Show tracebacks for errors.")
@click.version_option(package_name="footfall")
def cli(debug: bool) -> None:
    """footfall: learning where a legged robot should put its feet, with terrain templates."""


# ------------------------------------------------------------------- terrain
@cli.group()
def terrain() -> None:
    """Make, import and look at terrain height maps."""


def _map_summary(hmap, path: Path) -> tuple[dict, str]:
    import numpy as np

    h = hmap.heights
    data = {"file": str(path), "shape": list(hmap.shape), "resolution": hmap.resolution,
            "origin": list(hmap.origin), "bounds": list(hmap.bounds),
            "height_min": float(np.nanmin(h)), "height_max": float(np.nanmax(h)),
            "no_data_fraction": float(np.isnan(h).mean()), "hash": hmap.content_hash(),
            "metadata": hmap.metadata}
    text = (f"wrote {path}: {hmap.shape[0]} x {hmap.shape[1]} cells at "
            f"{hmap.resolution * 1000:g} mm, {hmap.length[0]:.3f} x {hmap.length[1]:.3f} m, "
            f"heights {data['height_min'] * 1000:.1f} .. {data['height_max'] * 1000:.1f} mm")
    return data, text


@terrain.command("make")
@click.argument("kind")
@click.option("--difficulty", type=float, default=0.5, show_default=True,
              help="Difficulty in [0, 1].")
@click.option("--seed", type=int, required=True, help="Random seed.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_make(kind: str, difficulty: float, seed: int, output: str, as_json: bool) -> None:
    """Make one 61 x 61 cm terrain module of KIND (flat, steps, barrier, slope, logs, rocky)."""
    from footfall.terrain import make_module

    out = _out_path(output)
    hmap = make_module(kind, difficulty, seed)
    hmap.save(out)
    _emit(as_json, *_map_summary(hmap, out))


@terrain.command("board")
@click.argument("specs", nargs=-1, required=True, metavar="KIND[:DIFFICULTY]...")
@click.option("--seed", type=int, required=True, help="Random seed.")
@click.option("--flat-ends/--no-flat-ends", default=True, show_default=True,
              help="Add a flat start and end module unless the row already has them.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_board(specs: tuple[str, ...], seed: int, flat_ends: bool, output: str,
                  as_json: bool) -> None:
    """Make a board: modules in a row along x, e.g. `rocky:0.5 rocky:0.8`."""
    from footfall.terrain import make_board, parse_module_spec

    out = _out_path(output)
    hmap = make_board([parse_module_spec(s) for s in specs], seed, flat_ends=flat_ends)
    hmap.save(out)
    _emit(as_json, *_map_summary(hmap, out))


@terrain.command("import")
@click.argument("source")
@click.option("--resolution", type=float, default=None,
              help="Cell size [m] (required for .npy, .png and point clouds).")
@click.option("--z-scale", type=float, default=None,
              help="Metres per raw height unit (required for 16-bit PNG).")
@click.option("--nodata", type=float, default=None, help="Raw value that means no data.")
@click.option("-o", "--output", required=True, help="Output height map (.npz).")
@json_option
def terrain_import(source: str, resolution: float | None, z_scale: float | None,
                   nodata: float | None, output: str, as_json: bool) -> None:
    """Import SOURCE (.npy, 16-bit .png, .ply, .xyz, .npz) as a footfall height map."""
    from footfall.terrain.scans import import_terrain

    out = _out_path(output)
    hmap = import_terrain(source, resolution=resolution, z_scale=z_scale, nodata=nodata)
    hmap.save(out)
    _emit(as_json, *_map_summary(hmap, out))


@terrain.command("show")
@click.argument("source")
@click.option("-o", "--output", required=True, help="Output picture (.png).")
@json_option
def terrain_show(source: str, output: str, as_json: bool) -> None:
    """Draw a shaded relief of a height map with a colour bar."""
    from footfall.core.heightmap import HeightMap
    from footfall.plots.relief import save_relief

    out = _out_path(output)
    hmap = HeightMap.load(source)
    save_relief(hmap, out, title=Path(source).name)
    _emit(as_json, {"file": str(out), "source": str(source)}, f"wrote {out}")


# ------------------------------------------------------------------ features
@cli.command()
@click.argument("source")
@click.option("--at", "at", nargs=2, type=float, required=True, metavar="X Y",
              help="Foothold position [m].")
@click.option("--yaw", type=float, default=0.0, show_default=True,
              help="Body heading [rad] that orients the patches.")
@click.option("--leg", type=click.Choice(["LF", "RF", "LH", "RH"]), default="LF",
              show_default=True, help="Swing leg (right legs see mirrored patches).")
@click.option("--template-resolution", type=float, default=None,
              help="Patch sample spacing [m] (default 0.003).")
@json_option
def features(source: str, at: tuple[float, float], yaw: float, leg: str,
             template_resolution: float | None, as_json: bool) -> None:
    """The 27 terrain features and three template patches of a foothold."""
    from footfall.core.heightmap import HeightMap
    from footfall.features.config import FeatureConfig
    from footfall.features.describe import describe_foothold

    hmap = HeightMap.load(source)
    config = FeatureConfig() if template_resolution is None else FeatureConfig(template_resolution)
    info = describe_foothold(hmap, at[0], at[1], yaw, leg, config)
    lines = [f"foothold ({at[0]:.4f}, {at[1]:.4f}) m, height {info['height'] * 1000:.2f} mm, "
             f"leg {leg}, yaw {yaw:.3f} rad"]
    lines += [f"  {name:24s} {value: .6g}" for name, value in info["terrain_features"].items()]
    lines += [f"  patch {n}: {p['shape'][0]} x {p['shape'][1]} samples at "
              f"{p['resolution'] * 1000:g} mm (use --json for the heights)"
              for n, p in info["patches"].items()]
    _emit(as_json, info, "\n".join(lines))


# --------------------------------------------------------------------- bench
@cli.group()
def bench() -> None:
    """Benchmarks: print figures, compared with a baseline run in the same process."""


@bench.command("scoring")
@click.option("--repeats", type=click.IntRange(1, 100), default=7, show_default=True)
@click.option("--baseline-sample", type=click.IntRange(10, 100000), default=300,
              show_default=True, help="Candidates timed with the per-candidate loop.")
@json_option
def bench_scoring_cmd(repeats: int, baseline_sample: int, as_json: bool) -> None:
    """Dense scoring of a 3-module board at 5 mm with 60 templates and 27 features."""
    from footfall.experiments.bench import bench_scoring, format_scoring

    result = bench_scoring(repeats=repeats, baseline_sample=baseline_sample)
    _emit(as_json, result, format_scoring(result))


@bench.command("learning")
@click.option("--demos", "n_demos", type=click.IntRange(10, 10000), default=100, show_default=True)
@click.option("--library-size", type=click.IntRange(3, 100000), default=1000, show_default=True)
@json_option
def bench_learning_cmd(n_demos: int, library_size: int, as_json: bool) -> None:
    """Paper-scale learning against scikit-learn's LogisticRegressionCV."""
    from footfall.experiments.bench import bench_learning, format_learning

    result = bench_learning(n_demos=n_demos, library_size=library_size)
    _emit(as_json, result, format_learning(result))


# ---------------------------------------------------------------------- demo
@cli.command()
@click.option("--out", "out", default="out/demo", show_default=True, help="Output folder.")
@click.option("--seed", type=int, default=0, show_default=True)
@json_option
def demo(out: str, seed: int, as_json: bool) -> None:
    """Build a board, score it densely and draw the terrain, features and templates."""
    from footfall.plots.showcase import run_demo

    result = run_demo(Path(out), seed=seed)
    _emit(as_json, result, "\n".join(f"wrote {p}" for p in result["files"]))


# --------------------------------------------------------------------- demos
@cli.group()
def demos() -> None:
    """Collect and inspect demonstrated footholds (a demonstration store, .sqlite)."""


def _terrain_label(info: dict) -> str:
    modules = info.get("metadata", {}).get("modules")
    if isinstance(modules, list) and modules and all(isinstance(m, dict) for m in modules):
        return ", ".join(str(m.get("kind")) if m.get("kind") == "flat" or m.get("difficulty")
                         is None else f"{m.get('kind')}:{m.get('difficulty')}" for m in modules)
    shape = info.get("shape", ["?", "?"])
    return f"{shape[0]} x {shape[1]} cells at {info.get('resolution', 0) * 1000:g} mm"


@demos.command("collect")
@click.option("--terrain", "terrains", multiple=True, required=True, metavar="FILE.npz",
              help="Terrain height map to walk on; more files may follow it.")
@click.argument("more_terrains", nargs=-1, metavar="[FILE.npz]...")
@click.option("-n", "--n", "n", type=click.IntRange(min=1), required=True,
              help="Number of demonstrations to add.")
@click.option("--seed", type=click.IntRange(min=0), required=True, help="Random seed.")
@click.option("-o", "--output", required=True,
              help="Demonstration store (.sqlite): appended to, created if missing.")
@click.option("--noise", type=click.FloatRange(min=0.0), default=None,
              help="Noise of the expert's foothold values (default: the expert's).")
@click.option("--second-best", type=click.FloatRange(0.0, 1.0), default=None,
              help="Probability that the expert picks its second-best foothold "
                   "(default: the expert's).")
@click.option("--steps", type=click.Choice(["rough", "all"]), default="rough", show_default=True,
              help="Record footholds on a board's non-flat modules only, or every step.")
@json_option
def demos_collect(terrains: tuple[str, ...], more_terrains: tuple[str, ...], n: int, seed: int,
                  output: str, noise: float | None, second_best: float | None, steps: str,
                  as_json: bool) -> None:
    """Add the synthetic expert's foothold choices on terrains to a store.

    The kinematic walker crosses each terrain along a few lateral paths in the
    crawl gait; the N demonstrations are spread over terrains and paths. The
    store is written in one transaction at the end: a failed or interrupted
    command leaves it as it was.
    """
    from tqdm import tqdm

    from footfall.core.heightmap import HeightMap
    from footfall.data.store import DemoStore
    from footfall.expert.collect import collect_demonstrations

    out = _out_path(output)
    hmaps = [HeightMap.load(path) for path in terrains + more_terrains]
    if out.exists():
        with DemoStore(out):  # refuse a bad store before walking, not after
            pass
    try:
        from footfall.expert.synthetic import ExpertConfig, SyntheticExpert
    except ImportError as exc:
        raise FootfallError(f"the synthetic expert is not available ({exc})") from None
    settings = {k: v for k, v in (("noise", noise), ("second_best_prob", second_best))
                if v is not None}
    expert = SyntheticExpert(config=ExpertConfig(**settings))
    with tqdm(total=n, unit="demo", desc="collect", file=sys.stderr, dynamic_ncols=True,
              disable=as_json or not sys.stderr.isatty()) as bar:
        collected = collect_demonstrations(hmaps, expert, n, seed, rough_only=steps == "rough",
                                           progress=lambda _: bar.update(1))
    if not collected:
        raise FootfallError("the walker recorded no demonstrations on these terrains "
                            "(too short, or no rough modules on its paths: try --steps all)")
    used = {d.terrain_hash for d in collected}
    with DemoStore(out, create=True) as store:
        ids = store.add_demonstrations(collected, terrains=[h for h in hmaps
                                                            if h.content_hash() in used])
        summary = store.summary()
    by_terrain: dict[str, int] = {}
    by_leg: dict[str, int] = {}
    for d in collected:
        by_terrain[d.terrain_hash] = by_terrain.get(d.terrain_hash, 0) + 1
        by_leg[d.swing_leg] = by_leg.get(d.swing_leg, 0) + 1
    data = {"store": str(out), "requested": n, "added": len(ids), "first_id": ids[0],
            "last_id": ids[-1], "added_by_terrain": by_terrain, "added_by_leg": by_leg,
            "expert": collected[0].expert, "seed": seed, "steps": steps,
            "total": summary["demonstrations"], "terrains": summary["terrains"]}
    text = (f"added {len(ids)} demonstrations (ids {ids[0]}..{ids[-1]}) to {out}: now "
            f"{summary['demonstrations']} on {summary['terrains']} "
            f"terrain{'s' if summary['terrains'] != 1 else ''}")
    if len(ids) < n:
        text += f" (only {len(ids)} of the {n} requested fit on these terrains)"
    _emit(as_json, data, text)


@demos.command("info")
@click.argument("store_path", metavar="DEMOS.sqlite")
@json_option
def demos_info(store_path: str, as_json: bool) -> None:
    """Count a store's demonstrations by terrain, swing leg and source; check the file."""
    from footfall.data.store import DemoStore

    with DemoStore(store_path) as store:
        store.check()
        summary = store.summary()
        terrains = store.terrain_info()
    data = {"store": str(store_path), **summary,
            "terrain_info": {h: {k: v for k, v in t.items() if k != "metadata"}
                             | {"label": _terrain_label(t)} for h, t in terrains.items()}}
    n_t = summary["terrains"]
    lines = [(f"{store_path}: {summary['demonstrations']} demonstrations on {n_t} "
              f"terrain{'s' if n_t != 1 else ''} "
              f"({summary['format']} v{summary['schema_version']})")]
    for digest, count in summary["by_terrain"].items():
        lines.append(f"  terrain {digest[:12]}  {count:6d}  {_terrain_label(terrains[digest])}")
    lines.append("  legs:    " + ", ".join(f"{k} {v}" for k, v in summary["by_leg"].items()))
    lines.append("  sources: " + (", ".join(f"{k} {v}" for k, v in summary["by_source"].items())
                                  or "none"))
    if summary["candidates"]:
        c = summary["candidates"]
        lines.append(f"  candidates per demonstration: {c['min']} .. {c['max']} "
                     f"(mean {c['mean']:.0f})")
    _emit(as_json, data, "\n".join(lines))


def _load_demos(store_path: str, ids: str | None = None, source: str | None = None):
    """All demonstrations of a store (or those with the given ids / source prefix) and a terrain lookup."""
    from footfall.data.store import DemoStore

    with DemoStore(store_path) as store:
        wanted = None if ids is None else [int(i) for i in ids.split(",") if i.strip()]
        demos = store.demonstrations(ids=wanted, source_prefix=source)
        if not demos:
            raise FootfallError(f"{store_path}: the store holds no demonstrations"
                                + ("" if source is None else f" from source {source!r}"))
        maps = {h: store.terrain(h) for h in {d.terrain_hash for d in demos}}
    return demos, maps


@cli.command()
@click.argument("store_path", metavar="DEMOS.sqlite")
@click.option("--features", "feature_set", type=click.Choice(["terrain", "templates", "both"]),
              required=True, help="Feature set (each with the pose features).")
@click.option("--learner", type=click.Choice(["l1", "l2", "svm"]), default="l1",
              show_default=True, help="L1 / L2 logistic regression or a linear SVM.")
@click.option("--library-size", type=click.IntRange(3, 100000), default=1000, show_default=True,
              help="Templates in the library, over the three scales.")
@click.option("--training-candidates", type=click.IntRange(1, 100000), default=100,
              show_default=True, help="Other candidates per demonstration used for pairs.")
@click.option("--bandwidth-rms", type=float, nargs=3, default=None, metavar="S M L",
              help="Fix the RBF bandwidths as RMS height differences [m] per scale "
                   "(default: chosen by cross-validation).")
@click.option("--cv", type=click.IntRange(2, 50), default=5, show_default=True)
@click.option("--selection", type=click.Choice(["1se", "min"]), default="1se", show_default=True,
              help="Lambda: one-standard-error rule (sparser) or the smallest CV error.")
@click.option("--source", default=None,
              help="Only demonstrations whose source starts with this (e.g. walker:train).")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("-o", "--output", required=True, help="Output model (.npz).")
@json_option
def learn(store_path: str, feature_set: str, learner: str, library_size: int,
          training_candidates: int, bandwidth_rms, cv: int, selection: str, source: str | None,
          seed: int, output: str, as_json: bool) -> None:
    """Learn front- and hind-leg foothold ranking functions from demonstrations."""
    from footfall.learning.train import TrainingDemo, learn_model

    out = _out_path(output)
    demos, maps = _load_demos(store_path, source=source)
    training = [TrainingDemo(maps[d.terrain_hash], d.state, d.candidates, d.chosen) for d in demos]
    log = (lambda s: None) if as_json else (lambda s: click.echo(s, err=True))
    model = learn_model(training, feature_set, learner, library_size=library_size,
                        training_candidates=training_candidates, bandwidth_rms=bandwidth_rms,
                        cv=cv, seed=seed, selection=selection, log=log)
    model.save(out)
    summary = {"model": str(out), "feature_set": feature_set, "learner": learner,
               "demonstrations": len(demos), "seconds": model.info["seconds"], "groups": {}}
    for g, f in model.functions.items():
        summary["groups"][g] = {
            "lambda": f.info["lambda"], "cv_error": f.info["cv_error"],
            "bandwidths_per_m2": list(getattr(f.family("templates"), "bandwidths", ())),
            "bandwidth_rms_m": f.info.get("bandwidth_rms_m"),
            "templates_kept": f.info.get("kept_counts", [0] * len(model.config.scales)),
            "library": f.info.get("library_counts", [0] * len(model.config.scales)),
            "non_zero_weights": f.info["n_nonzero"]}
    lines = [f"wrote {out}: {feature_set}/{learner} from {len(demos)} demonstrations "
             f"in {model.info['seconds']:.1f} s"]
    for g, v in summary["groups"].items():
        lines.append(f"  {g}: lambda {v['lambda']:.4g}, cv error {v['cv_error']:.4f}, "
                     f"templates kept {v['templates_kept']} of {v['library']}")
    _emit(as_json, summary, "\n".join(lines))


@cli.command("rank-eval")
@click.argument("model_path", metavar="MODEL.npz")
@click.argument("store_path", metavar="DEMOS.sqlite")
@click.option("--no-expert", is_flag=True, help="Skip the reward loss (needs the expert).")
@click.option("--source", default=None,
              help="Only demonstrations whose source starts with this (e.g. walker:train).")
@json_option
def rank_eval(model_path: str, store_path: str, no_expert: bool, source: str | None,
              as_json: bool) -> None:
    """Top-1 agreement, mean percentile rank and mean reward loss of a model on demonstrations."""
    from footfall.core.robot import LITTLEDOG
    from footfall.learning.evaluation import rank_scores
    from footfall.learning.model import FootholdModel

    model = FootholdModel.load(model_path)
    model.check_compatible(robot=LITTLEDOG)  # the robot whose states the store holds
    demos, maps = _load_demos(store_path, source=source)
    expert = None
    if not no_expert:
        from footfall.expert.synthetic import SyntheticExpert
        expert = SyntheticExpert(robot=model.robot)
    scores = rank_scores(model, demos, maps.__getitem__, expert)
    data = {"model": model_path, "feature_set": model.feature_set, "learner": model.learner,
            **scores.as_dict()}
    _emit(as_json, data, f"{model.feature_set}/{model.learner} on {scores.n} demonstrations: "
          f"top-1 {scores.top1:.3f}, within 1 cm {scores.top1_near:.3f}, "
          f"percentile {scores.percentile:.3f}, reward loss {scores.reward_loss:.3f} "
          f"(95 % CI {scores.reward_loss_ci[0]:.3f} to {scores.reward_loss_ci[1]:.3f})")


@cli.command()
@click.option("--out", "out", default="out/offline", show_default=True, help="Report folder.")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--quick", is_flag=True,
              help="A small version (fewer demonstrations, L1 only) for a smoke test.")
@json_option
def offline(out: str, seed: int, quick: bool, as_json: bool) -> None:
    """The offline experiment: learn from demonstrations, rank unseen terrain (Table I)."""
    from footfall.experiments.offline import OfflineConfig, run_offline

    config = OfflineConfig(seed=seed)
    if quick:
        config = OfflineConfig(seed=seed, n_train=30, n_test_modules=12, n_test_kind=8,
                               learners=("l1",), library_size=150,
                               train_difficulties=(0.5,), test_difficulties=(0.6,),
                               extra_rocky_train=1)
    log = (lambda s: None) if as_json else (lambda s: click.echo(s, err=True))
    summary = run_offline(Path(out), config, log=log)
    _emit(as_json, summary, f"wrote {Path(out) / 'report.md'}")


@cli.command()
@click.option("--out", "out", default="out/reproduce", show_default=True, help="Report folder "
              "(and the store of every run; run again with the same arguments to resume).")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True)
@click.option("--quick", is_flag=True, help="A small version (a few minutes) for a smoke test.")
@click.option("--processes", type=click.IntRange(min=1), default=None,
              help="Parallel runs [default: the available cores].")
@json_option
def reproduce(out: str, seed: int, quick: bool, processes: int | None, as_json: bool) -> None:
    """The paper's walking experiment end to end: corrections, learning, Tables I and II."""
    from footfall.experiments.reproduce import ReproduceConfig, run_reproduction

    config = ReproduceConfig.quick(seed) if quick else ReproduceConfig(seed=seed)
    log = (lambda s: None) if as_json else (lambda s: click.echo(s, err=True))
    results = run_reproduction(Path(out), config, processes=processes, log=log)
    t2 = results["table2"]
    _emit(as_json, results, "\n".join(
        [f"{k}: {v['successes']} / {v['runs']} succeeded, slip "
         + ("-" if v["slip_mean_mm"] is None else f"{v['slip_mean_mm']:.1f} +- {v['slip_std_mm']:.1f} mm")
         for k, v in t2.items()] + [f"wrote {Path(out) / 'report.md'} and report.html"]))


@bench.command("sim")
@click.option("--seed", type=click.IntRange(min=0), default=0, show_default=True)
@json_option
def bench_sim_cmd(seed: int, as_json: bool) -> None:
    """Real-time factor of the walking stack against bare MuJoCo stepping."""
    from footfall.experiments.bench import bench_sim, format_sim

    result = bench_sim(seed=seed)
    _emit(as_json, result, format_sim(result))


@bench.command("expert")
@click.option("--states", type=click.IntRange(1, 1000), default=16, show_default=True)
@json_option
def bench_expert_cmd(states: int, as_json: bool) -> None:
    """The walking expert's judgement with its placement error against without."""
    from footfall.experiments.bench import bench_expert, format_expert

    result = bench_expert(states=states)
    _emit(as_json, result, format_expert(result))


# --------------------------------------------------------------------- walking
def _load_terrain(path: str):
    from footfall.core.heightmap import HeightMap

    if not Path(path).exists():
        raise FootfallError(f"no such terrain file: {path}")
    return HeightMap.load(path)


def _run_text(result: dict) -> str:
    slip = ("" if result.get("slip_mean_mm") is None else
            f", slip {result['slip_mean_mm']:.1f} +- {result['slip_std_mm']:.1f} mm "
            f"({result['slip_count']} footholds)")
    return (f"{'success' if result['success'] else 'failure'} ({result['reason']}): "
            f"{result['distance']:.3f} m in {result['time']:.1f} s, {result['steps']} steps, "
            f"{result['speed_cm_s']:.1f} cm/s{slip}; real-time factor "
            f"{result['real_time_factor']:.1f}")


def _chooser_options(f):
    """--expert and --search-radius: who chooses the footholds, and among which."""
    f = click.option("--search-radius", type=float, default=None,
                     help="Candidate set F of a step: the footholds within this many metres of "
                          "the gait-nominal position (the reproduction uses 0.03); "
                          "default: every reachable one.")(f)
    return click.option("--expert", is_flag=True,
                        help="The synthetic walking expert chooses every foothold (no --model): "
                             "what learning from its demonstrations can reach at best.")(f)


def _walk_config(model_path: str | None, expert: bool, search_radius: float | None):
    """The walk settings of the command line, checked."""
    from dataclasses import replace

    from footfall.sim.episode import WalkConfig

    if expert and model_path is not None:
        raise FootfallError("--expert chooses the footholds itself: give no --model with it")
    base = WalkConfig()
    if search_radius is None:
        return base
    return replace(base, footstep=replace(base.footstep, search_radius=search_radius))


@cli.command("walk")
@click.option("--terrain", "terrain_path", required=True, help="Board height map (.npz).")
@click.option("--model", "model_path", default=None,
              help="Learned model (.npz); default: the hand-tuned reward.")
@click.option("--seed", type=click.IntRange(min=0), required=True,
              help="Run seed: start pose, terrain registration, friction, sensor noise.")
@click.option("--snapshots", default=None, help="Write a strip of frames (.png).")
@click.option("--frames", type=click.IntRange(2, 12), default=6, show_default=True,
              help="Frames in the snapshot strip.")
@click.option("--video", default=None, help="Write a video (.mp4).")
@click.option("--log", "log_path", default=None, help="Append the run log to this store (.sqlite).")
@_chooser_options
@json_option
def walk_cmd(terrain_path: str, model_path: str | None, seed: int, snapshots: str | None,
             frames: int, video: str | None, log_path: str | None, expert: bool,
             search_radius: float | None, as_json: bool) -> None:
    """One run of the simulated robot across a board (success, slip, speed)."""
    from footfall.experiments.batch import expert_judge, reward_source, save_strip, save_video
    from footfall.sim.episode import Frames, walk

    config = _walk_config(model_path, expert, search_radius)
    hmap = _load_terrain(terrain_path)
    reward_for = reward_source(model_path, hmap)
    for p in (snapshots, video):
        if p is not None:
            _out_path(p)
    store = None
    if log_path is not None:
        from footfall.data.store import DemoStore

        store = DemoStore(_out_path(log_path), create=True)  # checked before the run, not after
    pictures = None
    if snapshots or video:
        pictures = Frames(snapshot_count=frames if snapshots else 0,
                          video_fps=25.0 if video else 0.0)
    record = walk(hmap, reward_for, seed, config, frames=pictures,
                  judge=expert_judge(config) if expert else None)
    data = {"terrain": terrain_path, "model": model_path, "expert": expert, "seed": seed,
            **record.result}
    if snapshots:
        save_strip(pictures.snapshots, snapshots)
    if video:
        save_video(pictures.video, video, pictures.video_fps)
    if store is not None:
        with store:
            data["run_id"] = store.add_run(record, terrains=[hmap])
    _emit(as_json, data, _run_text(record.result))


@cli.command("walk-many")
@click.option("--terrain", "terrain_path", required=True, help="Board height map (.npz).")
@click.option("--model", "model_path", default=None,
              help="Learned model (.npz); default: the hand-tuned reward.")
@click.option("--runs", type=click.IntRange(min=1), default=21, show_default=True)
@click.option("--seed", type=click.IntRange(min=0), required=True,
              help="Run i has seed SEED + i.")
@click.option("--log", "log_path", default=None, help="Append every run log to this store.")
@_chooser_options
@json_option
def walk_many_cmd(terrain_path: str, model_path: str | None, runs: int, seed: int,
                  log_path: str | None, expert: bool, search_radius: float | None,
                  as_json: bool) -> None:
    """N runs in parallel processes: success rate (Wilson 95 % CI), slip, speed."""
    from tqdm import tqdm

    from footfall.experiments.batch import summarise, walk_many

    config = _walk_config(model_path, expert, search_radius)
    hmap = _load_terrain(terrain_path)
    store = None
    if log_path is not None:
        from footfall.data.store import DemoStore

        store = DemoStore(_out_path(log_path), create=True)
    with tqdm(total=runs, desc="runs", unit="run", disable=None, file=sys.stderr) as bar:
        def progress(record) -> None:
            bar.update(1)
            if store is not None:  # each finished run is kept at once
                store.add_run(record, terrains=[hmap])
        records = walk_many(terrain_path, model_path, runs, seed, config, progress=progress,
                            expert=expert)
    if store is not None:
        store.close()
    summary = summarise(records)
    d = summary.as_dict()
    data = {"terrain": terrain_path, "model": model_path, "expert": expert, "seed": seed, **d,
            "runs_detail": [{"seed": seed + i, **r.result} for i, r in enumerate(records)]}
    slip = ("no successful run" if summary.slip_mean_mm is None else
            f"slip {summary.slip_mean_mm:.1f} +- {summary.slip_std_mm:.1f} mm over "
            f"{summary.slip_count} footholds, {summary.speed_cm_s:.1f} cm/s")
    _emit(as_json, data, f"{summary.successes} / {summary.runs} succeeded "
          f"({100 * summary.success_rate:.1f} %, 95 % CI {100 * summary.success_ci[0]:.1f}-"
          f"{100 * summary.success_ci[1]:.1f} %); {slip}")


def main(argv: list[str] | None = None) -> int:
    """Entry point: run the CLI, turning user errors into one line and exit status 2."""
    args = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in args
    try:
        cli.main(args=args, prog_name="footfall", standalone_mode=False)
    except FootfallError as exc:
        if debug:
            raise
        click.echo(f"footfall: error: {exc}", err=True)
        return EXIT_USER_ERROR
    except click.exceptions.Abort:
        click.echo("footfall: interrupted", err=True)
        return 130
    except click.ClickException as exc:
        if debug:
            raise
        message = " ".join(exc.format_message().split())
        click.echo(f"footfall: error: {message} (see --help)", err=True)
        return EXIT_USER_ERROR
    except (OSError, MemoryError) as exc:
        if debug:
            raise
        click.echo(f"footfall: error: {exc}", err=True)
        return EXIT_USER_ERROR
    return 0


def _console() -> None:  # pragma: no cover - the console script
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
