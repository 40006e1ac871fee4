"""``footfall demos``: collect demonstrated footholds into a store, and count what a store holds."""

from __future__ import annotations

import click

from footfall.cli.choices import RECORDED_STEP, SEED, Finite, count_range
from footfall.cli.output import emit, json_option, progress_bar
from footfall.data.inventory import store_inventory
from footfall.expert.collect import collect_into_store


@click.group()
def demos() -> None:
    """Collect and inspect demonstrated footholds (a demonstration store, .sqlite)."""


def _plural(n: int, noun: str) -> str:
    return f"{noun}{'s' if n != 1 else ''}"


@demos.command("collect")
@click.option("--terrain", "terrains", multiple=True, required=True, metavar="FILE.npz",
              help="Terrain height map to walk on; more files may follow it.")
@click.argument("more_terrains", nargs=-1, metavar="[FILE.npz]...")
@click.option("-n", "--n", "n", type=count_range(1), required=True,
              help="Number of demonstrations to add.")
@click.option("--seed", type=SEED, required=True, help="Random seed.")
@click.option("-o", "--output", required=True,
              help="Demonstration store (.sqlite): appended to, created if missing.")
@click.option("--noise", type=Finite(min=0.0), default=None,
              help="Noise of the expert's foothold values (default: the expert's).")
@click.option("--second-best", type=Finite(0.0, 1.0), default=None,
              help="Probability that the expert picks its second-best foothold "
                   "(default: the expert's).")
@click.option("--steps", type=RECORDED_STEP, default="rough", show_default=True,
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
    with progress_bar(n, "collect", "demo", quiet=as_json) as step:
        added = collect_into_store(terrains + more_terrains, output, n, seed, noise=noise,
                                   second_best=second_best, steps=steps, progress=step)
    text = (f"added {added.added} demonstrations (ids {added.first_id}..{added.last_id}) to "
            f"{added.store}: now {added.total} on {added.terrains} "
            f"{_plural(added.terrains, 'terrain')}")
    if added.added < n:
        text += f" (only {added.added} of the {n} requested fit on these terrains)"
    emit(as_json, added.as_dict(), text)


@demos.command("info")
@click.argument("store_path", metavar="DEMOS.sqlite")
@json_option
def demos_info(store_path: str, as_json: bool) -> None:
    """Count a store's demonstrations by terrain, swing leg, source and labeler; check the file."""
    inventory = store_inventory(store_path)
    summary = inventory.summary
    lines = [(f"{store_path}: {summary['demonstrations']} demonstrations on "
              f"{summary['terrains']} {_plural(summary['terrains'], 'terrain')} "
              f"({summary['format']} v{summary['schema_version']})")]
    for digest, count in summary["by_terrain"].items():
        lines.append(f"  terrain {digest[:12]}  {count:6d}  {inventory.terrains[digest]['label']}")
    lines.append("  legs:    " + ", ".join(f"{k} {v}" for k, v in summary["by_leg"].items()))
    lines.append("  sources: " + (", ".join(f"{k} {v}" for k, v in summary["by_source"].items())
                                  or "none"))
    for name, verdicts in summary["labels"]["by_labeler"].items():
        lines.append(f"  labeler {name}: {verdicts['foothold']} footholds labelled, "
                     f"{verdicts['fine']} choices marked fine")
    if summary["labels"]["disagreements"]:
        lines.append(f"  labelers disagree on {summary['labels']['disagreements']} "
                     f"{_plural(summary['labels']['disagreements'], 'step')}")
    if summary["candidates"]:
        c = summary["candidates"]
        lines.append(f"  candidates per demonstration: {c['min']} .. {c['max']} "
                     f"(mean {c['mean']:.0f})")
    emit(as_json, inventory.as_dict(), "\n".join(lines))
