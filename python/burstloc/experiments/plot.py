"""``burstloc evaluate --plot DIR``: PNG figures of an evaluation (matplotlib, Agg backend).

Per run, two figures:

* ``<network>_<detector>_<mode>_<interval>s_network.png``: one small map per burst, the true
  pipe in green and the named pipe in red (a correct answer is green only, "not located" is
  said in the panel title);
* ``<network>_<detector>_<mode>_<interval>s_traces_<pipe>.png``: for one chosen burst (the
  first pipe evaluated, or ``pipe``), every meter's readings at phase 0 around the burst, the
  deciding window shaded, each alarmed meter's change starts marked and the trigger meter drawn
  thicker.

matplotlib is imported only when a figure is drawn.
"""

from __future__ import annotations

import io
import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from burstloc._atomic import write_bytes
from burstloc.experiments.evaluate import Evaluation, RunResult
from burstloc.sim.capture import resample

__all__ = ["plot_accuracy_by_interval", "plot_network", "plot_traces", "write_plots"]

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save(plt: Any, fig: Any, path: str | os.PathLike[str]) -> Path:
    """Write ``fig`` as a PNG to ``path`` (atomically) and close it."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    return write_bytes(path, buffer.getvalue())


def _stem(ev: Evaluation, r: RunResult) -> str:
    net = Path(ev.network).stem
    ci = f"{r.spec.capture_interval:g}".replace(".", "p")
    return _UNSAFE.sub("_", f"{net}_{r.spec.detector.kind}_{r.spec.mode.value}_{ci}s")


def _positions(graph: Any) -> dict[str, tuple[float, float]]:
    pos = {n: d.get("pos") for n, d in graph.nodes(data=True)}
    if any(p is None for p in pos.values()):
        import networkx as nx

        return dict(nx.spring_layout(graph, seed=0))
    return {n: (float(p[0]), float(p[1])) for n, p in pos.items()}


def plot_network(ev: Evaluation, r: RunResult, path: str | os.PathLike[str]) -> Path:
    """One map per burst of run ``r``: true pipe green, named pipe red (phase 0)."""
    plt = _pyplot()
    graph = ev.graph
    pos = _positions(graph)
    n = len(r.pipes)
    cols = min(5, n)
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.6 * rows), squeeze=False)
    edges = list(graph.edges(data=True))
    for ax, pipe in zip(axes.flat, r.pipes, strict=False):
        a = r.attempts[pipe][0]
        for u, v, _ in edges:
            (x0, y0), (x1, y1) = pos[u], pos[v]
            ax.plot([x0, x1], [y0, y1], color="0.8", lw=1, zorder=1)
        xs, ys = zip(*pos.values(), strict=True)
        ax.scatter(xs, ys, s=6, color="0.5", zorder=2)
        t0, t1 = r.truth[pipe]
        ax.plot(*zip(pos[t0], pos[t1], strict=True), color="tab:green", lw=4, zorder=3)
        if a.predicted is not None and not a.correct:
            p0, p1 = a.predicted
            ax.plot(*zip(pos[p0], pos[p1], strict=True), color="tab:red", lw=3, zorder=4)
        if not a.located:
            status = "not located"
        elif a.localization is None:  # a ranking localizer
            status = "correct" if a.correct else f"named {a.predicted_pipe}"
            status += f" ({r.spec.localizer}, rank {a.ranking.rank_of(pipe) if a.ranking else '-'})"
        else:
            status = ("correct" if a.correct else f"named {a.localization.pipe}") + (
                f" ({a.localization.rule.value})"
            )
        ax.set_title(f"pipe {pipe}: {status}", fontsize=7)
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_aspect("equal", adjustable="datalim")
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.suptitle(
        f"{Path(ev.network).name}: {r.spec.detector.kind}, mode {r.spec.mode.value}, "
        f"capture {r.spec.capture_interval:g} s - {r.correct}/{r.total} correct (phase 0)",
        fontsize=10,
    )
    fig.tight_layout()
    return _save(plt, fig, path)


def plot_traces(ev: Evaluation, r: RunResult, pipe: str, path: str | os.PathLike[str]) -> Path:
    """The meters' readings around the burst on ``pipe`` (phase 0) with the alarms."""
    plt = _pyplot()
    result = ev.results[pipe]
    a = r.attempts[pipe][0]
    loc = a.localization
    ci = r.spec.capture_interval
    times, values = resample(result.time, result.heads, ci, 0.0)
    start = a.burst_start
    window = 2 * r.spec.localization_interval * ci
    end = loc.decision_time + window if loc else start + 2 * window
    keep = (times >= start - window) & (times <= end)
    fig, ax = plt.subplots(figsize=(10, 5))
    for j, meter in enumerate(result.junctions):
        trigger = loc is not None and meter == loc.trigger_node
        (line,) = ax.plot(
            times[keep],
            values[keep, j],
            lw=2.5 if trigger else 0.9,
            label=meter,
            drawstyle="steps-post",
        )
        if loc is not None and meter in loc.evidence:
            for c in loc.evidence[meter]:
                k = int(np.searchsorted(times, c.start_time))
                if 0 <= k < times.size:
                    ax.plot(times[k], values[k, j], ">", color=line.get_color(), ms=7)
    ax.axvline(start, color="k", ls="--", lw=1, label="burst start")
    if loc is not None:
        ax.axvspan(loc.decision_time - window + ci, loc.decision_time, color="0.9", zorder=0)
        title = (
            f"pipe {pipe} burst: named {loc.pipe} ({loc.start_node} - {loc.end_node}) by "
            f"{loc.rule.value}, trigger {loc.trigger_node}, "
            f"{loc.decision_time - start:.2f} s after the burst"
        )
    else:
        title = f"pipe {pipe} burst: not located"
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("pressure head (m)")
    ax.legend(fontsize=7, ncol=2, loc="lower left")
    fig.tight_layout()
    return _save(plt, fig, path)


def write_plots(
    ev: Evaluation, directory: str | os.PathLike[str], pipe: str | None = None
) -> list[Path]:
    """Write both figures for every run into ``directory``; return the paths."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    for r in ev.runs:
        chosen = pipe if pipe is not None else r.pipes[0]
        stem = _stem(ev, r)
        paths.append(plot_network(ev, r, out / f"{stem}_network.png"))
        safe = _UNSAFE.sub("_", chosen)
        paths.append(plot_traces(ev, r, chosen, out / f"{stem}_traces_{safe}.png"))
    return paths


def plot_accuracy_by_interval(
    rows: Sequence[Mapping[str, Any]],
    path: str | os.PathLike[str],
    title: str,
    series_keys: Sequence[str],
) -> Path:
    """Top-1 accuracy (%) against the capture interval (log axis), one panel per meter model
    and one line per value of ``series_keys`` (study rows: ``capture_interval``, ``top1``,
    ``meter_model`` and the series keys)."""
    plt = _pyplot()

    models = sorted({r["meter_model"] for r in rows})
    fig, axes = plt.subplots(1, len(models), figsize=(5 * len(models), 3.6), squeeze=False)
    for ax, model in zip(axes[0], models, strict=True):
        series: dict[tuple[Any, ...], list[tuple[float, float]]] = {}
        for r in rows:
            if r["meter_model"] == model:
                key = tuple(r[k] for k in series_keys)
                series.setdefault(key, []).append((r["capture_interval"], 100 * r["top1"]))
        for key, pts in sorted(series.items(), key=lambda kv: str(kv[0])):
            pts.sort()
            ax.plot(
                [p[0] for p in pts], [p[1] for p in pts], marker="o", label=" ".join(map(str, key))
            )
        ax.set_xscale("log")
        ax.set_xlabel("capture interval (s)")
        ax.set_ylabel("top-1 accuracy (%)")
        ax.set_ylim(-2, 102)
        ax.set_title(f"{title} - {model}", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(plt, fig, path)
