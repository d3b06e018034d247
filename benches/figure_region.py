"""The figure of the search region as it narrows: one burst, its meters, its early and its final
region (``docs/img/search-region.png``).

Usage: ``.venv/bin/python benches/figure_region.py [NETWORK.inp] [--meters K] [--pipe ID]
[--out PNG]``. Default: EPANET's Net2 (``make networks``) with 4 meters placed by ``burstloc
place`` (about 10 % of its junctions), a burst at mid-pipe, the CUSUM bank calibrated at 0.2 s,
the fused localizer, the calibrated sensor noise: ``burstloc evaluate``'s scoring run on the
burst (phase 0). Without ``--pipe`` the pipe is the one whose answer narrowed its early record's
region the most (and held the burst). Left: the early (transient) record,
from the arrivals alone; right: the answer, with the lasting drop. The burst point is the
black cross; the meters are the squares.
"""

from __future__ import annotations

import argparse
import itertools
import math
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]


def _draw(ax: Any, layout: Any, decision: Any, truth: Any, meters: list[str], title: str) -> None:
    """One panel: the network in grey, the region's stretches in orange, meters and burst."""
    nodes, links = layout.nodes, layout.links

    def along(pipe: str, start: str, fraction: float) -> tuple[float, float]:
        _, a, b, vertices = links[pipe]
        pts = [nodes[a][1:], *vertices, nodes[b][1:]]
        if start != a:
            pts = pts[::-1]
        pairs = list(itertools.pairwise(pts))
        seg = [math.hypot(x1 - x0, y1 - y0) for (x0, y0), (x1, y1) in pairs]
        goal, run = fraction * sum(seg), 0.0
        for ((x0, y0), (x1, y1)), s in zip(pairs, seg, strict=True):
            if run + s >= goal and s > 0:
                t = (goal - run) / s
                return x0 + t * (x1 - x0), y0 + t * (y1 - y0)
            run += s
        return pts[-1]

    for _, a, b, vertices in links.values():
        xs, ys = zip(nodes[a][1:], *vertices, nodes[b][1:], strict=True)
        ax.plot(xs, ys, color="#bbbbbb", lw=1.0, zorder=1)
    region = decision.region
    metres = {p.pipe: p.length for p in decision.posterior.grid.arrival.pipes}  # SI, not the file's
    for s in region.stretches:
        length = metres[s.pipe]
        pts = [along(s.pipe, s.start, f) for f in _fractions(s.low / length, s.high / length)]
        xs, ys = zip(*pts, strict=True)
        ax.plot(xs, ys, color="#ff8c00", lw=5.0, alpha=0.85, zorder=2, solid_capstyle="butt")
    for m in meters:
        x, y = nodes[m][1:]
        ax.scatter([x], [y], marker="s", s=60, zorder=4, color="#1f4e9a")
    x, y = along(truth.pipe, truth.node, truth.metres / metres[truth.pipe])
    ax.scatter([x], [y], marker="X", s=140, color="black", zorder=5)
    ax.set_title(
        f"{title}\n95 % region: {region.length:.0f} m on {len({s.pipe for s in region.stretches})}"
        f" pipe(s), t = {decision.time:.1f} s",
        fontsize=10,
    )
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def _fractions(low: float, high: float) -> list[float]:
    return [low + (high - low) * k / 20 for k in range(21)]


def main() -> None:
    """Run the burst, draw both records."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from burstloc.experiments.evaluate import evaluate
    from burstloc.experiments.runs import ranking_runs
    from burstloc.layout import read_layout
    from burstloc.sim.placement.methods import place_meters

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("network", nargs="?", default=str(REPO / "networks/public/Net2.inp"))
    parser.add_argument("--meters", type=int, default=4)
    parser.add_argument("--pipe")
    parser.add_argument("--out", default=str(REPO / "docs/img/search-region.png"))
    args = parser.parse_args()
    meters = list(place_meters(args.network, args.meters).meters)
    runs = ranking_runs(["cusum"], [0.2], ["fused"])
    pipes = None if args.pipe is None else [args.pipe]
    ev = evaluate(args.network, runs, meters=meters, pipes=pipes, phases=1, progress=False)
    (run,) = ev.runs
    chosen, best = None, 1.0
    for p in run.pipes:
        a = run.attempts[p][0]
        if a.decision is None or a.decision.region is None or not a.early:
            continue
        early = a.early[0].region
        covered = run.regions[p][0].covered
        if early is not None and covered and covered[-1]:
            ratio = early.length / max(a.decision.region.length, 1.0)
            if ratio > best:
                chosen, best = p, ratio
    if chosen is None:
        raise SystemExit("no burst with an early record narrowed by its answer")
    attempt = run.attempts[chosen][0]
    layout = read_layout(args.network)
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 5.6))
    truth = run.points[chosen]
    _draw(axes[0], layout, attempt.early[0], truth, meters, "early record: the arrivals")
    _draw(axes[1], layout, attempt.decision, truth, meters, "answer: with the lasting drop")
    fig.suptitle(
        f"{Path(args.network).name}: burst on pipe {chosen}, {len(meters)} meters "
        f"({', '.join(meters)}), 0.2 s readings",
        fontsize=11,
    )
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}: pipe {chosen}, early {attempt.early[0].region.length:.0f} m -> "
          f"answer {attempt.decision.region.length:.0f} m")  # fmt: skip


if __name__ == "__main__":
    main()
