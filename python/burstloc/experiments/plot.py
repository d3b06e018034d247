"""``burstloc evaluate --plot DIR``: PNG figures of an evaluation (matplotlib, Agg backend).

Per run, two figures:

* ``<network>_<detector>_<mode>_<interval>s_network.png``: one small map per burst, the true
  pipe in green and the named pipe in red (a correct answer is green only, "not located" is
  said in the panel title);
* ``<network>_<detector>_<mode>_<interval>s_traces_<pipe>.png``: for one chosen burst (the
  first pipe evaluated, or ``pipe``), every meter's readings at phase 0 around the burst, each
  alarmed meter's change start marked, the decision time drawn (the paper's rules: the deciding
  window shaded and the trigger meter thicker), titled with what the run said.

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
from burstloc.sim.scenarios.capture import resample

__all__ = ["plot_accuracy_by_interval", "plot_network", "plot_traces", "trace_title", "write_plots"]

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
        _label(ax, pos[t0], pos[t1], pipe, "tab:green")
        if a.predicted is not None and not a.correct:
            p0, p1 = a.predicted
            ax.plot(*zip(pos[p0], pos[p1], strict=True), color="tab:red", lw=3, zorder=4)
            _label(ax, pos[p0], pos[p1], a.predicted_pipe or "", "tab:red")
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
        f"{Path(ev.network).name}: {r.spec.localizer} localizer, {r.spec.detector.kind}, mode "
        f"{r.spec.mode.value}, capture {r.spec.capture_interval:g} s - {r.correct}/{r.total} "
        "correct (phase 0); green: burst pipe, red: pipe named instead",
        fontsize=9,
    )
    fig.tight_layout(rect=(0.0, 0.0, 1.0, 1.0 - 0.35 / fig.get_figheight()))  # room for the title
    return _save(plt, fig, path)


def _label(ax: Any, a: tuple[float, float], b: tuple[float, float], text: str, color: str) -> None:
    """``text`` at the middle of the segment ``a``-``b``, in ``color``."""
    ax.annotate(
        text,
        ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2),
        fontsize=7,
        color=color,
        fontweight="bold",
        xytext=(5, 5),
        textcoords="offset points",
        ha="left",
        zorder=5,
        bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8},
    )


def _ranked_alarms(ev: Evaluation, r: RunResult, pipe: str) -> dict[str, float]:
    """Each alarmed meter's first alarm (the change's start time) in a ranking localizer's run
    at phase 0: the readings and calibrated bank of that run, again."""
    from burstloc.experiments.harness import readings_at_offset
    from burstloc.localize.interval import calibrated_bank

    setup = ev.setup
    if setup is None:
        return {}
    times, values = readings_at_offset(ev.results[pipe], r.spec, 0.0, meters=setup.meters)
    cal = setup.config.for_interval(r.spec.capture_interval)
    bank = calibrated_bank(r.spec.detector.kind, len(setup.meters), cal)
    first: dict[str, float] = {}
    for alarm in bank.run(np.ascontiguousarray(values)):
        meter = setup.meters[int(alarm.channel or 0)]
        first.setdefault(meter, float(times[alarm.start]))
    return first


def trace_title(r: RunResult, pipe: str, start: float) -> str:
    """What the run said of the burst on ``pipe`` at phase 0: the named pipe, right or wrong,
    by which rule or localizer, and when."""
    a = r.attempts[pipe][0]
    loc, decision = a.localization, a.decision
    if loc is not None:
        return (
            f"pipe {pipe} burst: named {loc.pipe} ({loc.start_node} - {loc.end_node}), "
            f"{'correct' if a.correct else 'wrong'}, by {loc.rule.value}, trigger "
            f"{loc.trigger_node}, {loc.decision_time - start:.2f} s after the burst"
        )
    if decision is not None and a.predicted_pipe is not None:
        return (
            f"pipe {pipe} burst: named {a.predicted_pipe}, {'correct' if a.correct else 'wrong'}"
            f" ({r.spec.localizer} localizer), first alarm {decision.first_alarm - start:.2f} s "
            f"and decision {decision.time - start:.2f} s after the burst"
        )
    return f"pipe {pipe} burst: not located ({r.spec.localizer})"


def plot_traces(ev: Evaluation, r: RunResult, pipe: str, path: str | os.PathLike[str]) -> Path:
    """The meters' readings around the burst on ``pipe`` (phase 0) with the alarms: each
    alarmed meter's change start marked (``>``), the decision time and, for the paper's rules,
    the deciding window shaded; the title says what the run said."""
    plt = _pyplot()
    result = ev.results[pipe]
    a = r.attempts[pipe][0]
    loc, decision = a.localization, a.decision
    ci = r.spec.capture_interval
    times, values = resample(result.time, result.heads, ci, 0.0)
    start = a.burst_start
    window = 2 * r.spec.localization_interval * ci
    if loc is not None:
        decided: float | None = loc.decision_time
        alarms = {m: c[0].start_time for m, c in loc.evidence.items() if c}
    else:
        decided = None if decision is None else decision.time
        alarms = _ranked_alarms(ev, r, pipe) if decision is not None else {}
    # around the alarms; a decision much later (the fused localizer waiting for the signature)
    # is marked at the right edge instead of squeezing the transient into a sliver
    end = max(start + 2 * window, max(alarms.values(), default=start) + window)
    if decided is not None and decided - start <= 5 * window:
        end = max(end, decided + window)
    keep = (times >= start - window) & (times <= end)
    fig, ax = plt.subplots(figsize=(10, 5.4))
    for j, meter in enumerate(result.junctions):
        trigger = loc is not None and meter == loc.trigger_node
        alarmed = meter in alarms
        (line,) = ax.plot(
            times[keep],
            values[keep, j],
            lw=2.5 if trigger else (1.3 if alarmed else 0.7),
            label=f"{meter} (alarm)" if alarmed else meter,
            drawstyle="steps-post",
            alpha=1.0 if alarmed else 0.6,
        )
        if alarmed:
            k = int(np.searchsorted(times, alarms[meter]))
            if 0 <= k < times.size:
                ax.plot(times[k], values[k, j], ">", color=line.get_color(), ms=8, mec="k")
    ax.axvline(start, color="k", ls="--", lw=1, label="burst start")
    if decided is not None and decided <= end:
        ax.axvline(decided, color="tab:red", ls=":", lw=1.5, label="decision")
    elif decided is not None:
        ax.annotate(
            f"decision at {decided:g} s ->",
            (1.0, 0.97),
            xycoords="axes fraction",
            ha="right",
            va="top",
            fontsize=8,
            color="tab:red",
        )
    if loc is not None:
        ax.axvspan(loc.decision_time - window + ci, loc.decision_time, color="0.9", zorder=0)
    ax.set_title(trace_title(r, pipe, start), fontsize=9, wrap=True)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("pressure head (m)")
    ax.legend(fontsize=7, ncol=2, loc="lower left", title="meters; > alarm start", title_fontsize=7)
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
