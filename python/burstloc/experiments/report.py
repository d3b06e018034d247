"""Print and write an :class:`~burstloc.experiments.evaluate.Evaluation`: the paper's tables,
JSON, CSV.

* :func:`format_tables`: per detector and mode, the per-pipe predictions of every run (phase 0)
  beside the paper's Tables III/IV when the run is one of the paper's, then a summary in the
  shape of Table V (accuracy at phase 0, phase mean with min-max, the paper's figure, median
  time to localize).
* :func:`write_json`: the CLI's JSON contract (``tests/evaluate_schema.json``).
* :func:`write_csv`: one row per run and pipe.

The robustness study's report is :mod:`burstloc.experiments.study_report`.

Every file is written atomically (:mod:`burstloc._atomic`).
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from burstloc import _atomic as atomic
from burstloc.constants import CAPTURE_INTERVALS
from burstloc.experiments import paper
from burstloc.experiments.evaluate import Evaluation, RunResult
from burstloc.experiments.position import PositionErrors, PositionOutcome
from burstloc.experiments.region_score import REGION_HEADER, RegionOutcome, region_cells

__all__ = [
    "CSV_FIELDS",
    "format_tables",
    "is_paper_network",
    "pct",
    "write_csv",
    "write_json",
]

#: Columns of :func:`write_csv`.
CSV_FIELDS: tuple[str, ...] = (
    "detector",
    "mode",
    "capture_interval",
    "threshold",
    "drift",
    "sigma",
    "localization_interval",
    "pipe",
    "true_start",
    "true_end",
    "predicted_start",
    "predicted_end",
    "correct",
    "time_to_localize_s",
    "rule",
    "trigger_node",
    "phases_correct",
    "phases",
    "position_m",
    "position_from",
    "position_error_m",
    "region_m",
    "region_pipes",
    "region_holds_burst",
)

_TABLE_NAMES = {"cusum": ("III", "CUSUM"), "shewhart": ("IV", "Shewhart")}


def _pair(p: Sequence[str] | None) -> str:
    return "not located" if p is None else f"{p[0]} - {p[1]}"


def pct(x: float | None, unit: str = "%") -> str:
    """``x`` (a share) as a whole percentage (``-`` for ``None``)."""
    return "-" if x is None else f"{100 * x:.0f}{unit}"


def _groups(ev: Evaluation) -> list[tuple[str, str, list[RunResult]]]:
    groups: dict[tuple[str, str], list[RunResult]] = {}
    for r in ev.runs:
        groups.setdefault((r.spec.detector.kind, r.spec.mode.value), []).append(r)
    return [
        (k, m, sorted(rs, key=lambda r: r.spec.capture_interval)) for (k, m), rs in groups.items()
    ]


def _pipe_order(pipes: Sequence[str]) -> list[str]:
    known = [p for p in paper.PAPER_PIPES if p in pipes]
    return known + [p for p in pipes if p not in paper.PAPER_PIPES]


def _render(rows: list[list[str]], header: list[str]) -> list[str]:
    widths = [max(len(str(c)) for c in col) for col in zip(header, *rows, strict=True)]
    line = "  ".join(h.ljust(w) for h, w in zip(header, widths, strict=True)).rstrip()
    out = [line, "-" * len(line)]
    out += [
        "  ".join(str(c).ljust(w) for c, w in zip(row, widths, strict=True)).rstrip()
        for row in rows
    ]
    return out


def _run_title(r: RunResult, framed: bool = True) -> str:
    label = r.spec.paper_run()
    name = label.scenario if label and framed else "run"
    if r.spec.localizer != "paper" or not framed:
        short = "avg" if r.spec.meter_model == "interval-averaged" else "inst"
        name = f"{r.spec.localizer}/{short}"
    return f"{name} {r.spec.capture_interval:g}s"


def noise_line(ev: Evaluation) -> str:
    """What noise the readings carried (``ev.scenario["noise"]``), in one line."""
    noise = ev.scenario.get("noise") or {}

    def said(sigma: Any) -> str:
        if isinstance(sigma, dict):
            levels = sorted(set(sigma.values()))
            if not levels or levels == [0.0]:
                return "none"
            span = f"{levels[0]:g} m" if len(levels) == 1 else f"{levels[0]:g}-{levels[-1]:g} m"
            return f"the calibrated sigma = {span}"
        return "none" if not sigma else f"sigma = {sigma:g} m"

    parts = []
    if any(r.spec.localizer == "paper" for r in ev.runs):
        parts.append(f"paper's rules: {said(noise.get('paper'))}")
    if any(r.spec.localizer != "paper" for r in ev.runs):
        parts.append(f"ranking localizers: {said(noise.get('ranking'))}")
    seed = ev.scenario.get("noise_seed", 0)
    return f"Sensor noise on the readings ({'; '.join(parts)}; seed {seed}; --noise sets it)"


def is_paper_network(ev: Evaluation) -> bool:
    """Whether ``ev`` evaluated the paper's network (``networks/paper15.inp``): every burst
    pipe is one of the paper's, between the paper's nodes in flow direction."""
    truth = ev.runs[0].truth if ev.runs else {}
    return bool(truth) and all(_pair(truth[p]) == paper.TRUE_PIPES.get(p) for p in truth)


def format_tables(ev: Evaluation, paper_tables: bool | None = None) -> str:
    """The per-pipe tables and the summary as text (``*`` marks a correct pipe).

    With ``paper_tables`` (default: on the paper's network only, :func:`is_paper_network`) they
    are framed as the paper's Tables III-V, with the paper's figures beside ours; otherwise
    they carry no figure of the paper's, whose network is another.
    """
    framed = is_paper_network(ev) if paper_tables is None else paper_tables
    out: list[str] = [noise_line(ev)]
    for kind, mode, runs in _groups(ev):
        number, name = _TABLE_NAMES[kind]
        pipes = _pipe_order(runs[0].pipes)
        out.append("")
        if framed:
            out.append(
                f"Table {number} ({name}, detection mode '{mode}'): burst pipe named at phase 0, "
                "'*' = correct; 'paper' = the paper's Table " + number
            )
        else:
            out.append(
                f"{name}, detection mode '{mode}': burst pipe named at phase 0, '*' = correct"
            )
        header = ["pipe", "true"]
        for r in runs:
            header.append(_run_title(r, framed))
            if framed and r.spec.paper_run() is not None:
                header.append("paper")
        rows: list[list[str]] = []
        for p in pipes:
            row = [p, _pair(runs[0].truth[p])]
            for r in runs:
                a = r.attempts[p][0]
                row.append(_pair(a.predicted) + (" *" if a.correct else ""))
                pr = r.spec.paper_run()
                if framed and pr is not None:
                    if p in paper.TRUE_PIPES:
                        pub = paper.published_prediction(kind, p, pr.capture_interval)
                        row.append(pub + (" *" if pub == paper.TRUE_PIPES[p] else ""))
                    else:
                        row.append("-")
            rows.append(row)
        total = ["correct", ""]
        for r in runs:
            total.append(f"{r.correct}/{r.total}")
            pr = r.spec.paper_run()
            if framed and pr is not None:
                k = CAPTURE_INTERVALS.index(pr.capture_interval)
                total.append(
                    f"{paper.published_correct(kind)[k]}/25 "
                    f"(printed {paper.PRINTED_TOTALS[kind][k]})"
                )
        rows.append(total)
        out += _render(rows, header)

    out.append("")
    out.append(
        f"{'Table V' if framed else 'Summary'}: accuracy (eq. 4) at phase 0, and mean [min-max] "
        f"over {len(ev.runs[0].offsets)} phase(s) spread over one "
        f"{'capture interval' if ev.phase_span == 'capture' else 'localization window'}; "
        + (
            "paper = Table V; "
            if framed
            else "top-1 / top-3 = the burst pipe named first / among the first three; "
        )
        + "time = median time to localize; position error = network distance "
        "from the true burst point to the named position, over every attempt (mean interval width, "
        "intervals on the burst pipe that held the true point)"
    )
    header = [
        "detector",
        "mode",
        "capture",
        "params",
        "phase 0",
        "phase mean [min-max]",
        *(["paper"] if framed else []),
        "median time",
        "localizer",
        "top-1 / top-3",
        "position error mean / p90 (interval)",
    ]
    rows = []
    for kind, mode, runs in _groups(ev):
        for r in runs:
            acc = r.phase_accuracies()
            pr = r.spec.paper_run()
            pub = "-"
            if pr is not None:
                k = CAPTURE_INTERVALS.index(pr.capture_interval)
                pub = f"{paper.TABLE_V[kind][k]:.0f}%"
            tally = r.tally()
            ttl = tally.median_time()
            params = (
                "calibrated"
                if r.spec.localizer != "paper"
                else ", ".join(f"{k}={v:g}" for k, v in r.spec.detector.params().items())
                + f", L={r.spec.localization_interval}"
            )
            rows.append(
                [
                    _TABLE_NAMES[kind][1],
                    mode,
                    f"{r.spec.capture_interval:g} s",
                    params,
                    f"{r.correct}/{r.total} = {pct(r.accuracy)}",
                    f"{100 * sum(acc) / len(acc):.1f}% [{pct(min(acc))}-{pct(max(acc))}]",
                    *([pub] if framed else []),
                    "-" if ttl is None else f"{ttl:.2f} s",
                    f"{r.spec.localizer} ({r.spec.meter_model})",
                    f"{pct(tally.top1_fraction)} / {pct(tally.top3_fraction)}",
                    _metres(r.position_errors()),
                ]
            )
    out += _render(rows, header)
    ranked = [r for _, _, runs in _groups(ev) for r in runs if r.spec.localizer != "paper"]
    if ranked:
        out += ["", _REGION_TITLE]
        rows = [
            [
                _TABLE_NAMES[r.spec.detector.kind][1],
                f"{r.spec.capture_interval:g} s",
                f"{r.spec.localizer} ({r.spec.meter_model})",
                *region_cells(r.region_scores()),
            ]
            for r in ranked
        ]
        out += _render(rows, ["detector", "capture", "localizer", *REGION_HEADER])
    for w in ev.warnings:
        out.append(f"warning: {w}")
    return "\n".join(out).lstrip("\n") + "\n"


_REGION_TITLE = (
    "Search regions, over every attempt: the median time from the burst to the first record "
    "with a region; the share of bursts inside the region stated to hold "
    "them with 50 / 80 / 95 % (an attempt without an answer holds nothing); the 95 % region's "
    "median / p90 length in metres of main; the named point within 100 / 300 m network "
    "distance of the burst; the share with a 95 % region of at most 1 km, and the median time "
    "from the burst to it"
)


def _metres(errors: PositionErrors) -> str:
    """``mean / p90 m (width m, hits/on-pipe held)`` of a run's position errors: mean interval
    width, and how many intervals on the burst pipe held the true point; ``-`` without any."""
    if errors.mean is None or errors.p90 is None or errors.mean_width is None:
        return "-"
    held = f", {errors.interval_hits}/{errors.on_pipe} held" if errors.on_pipe else ""
    return f"{errors.mean:.0f} / {errors.p90:.0f} m ({errors.mean_width:.0f} m{held})"


def write_json(ev: Evaluation, path: str | os.PathLike[str]) -> Path:
    """Write the evaluation as the CLI's JSON document."""
    return atomic.write_json(path, ev.to_json())


def _csv_rows(ev: Evaluation) -> list[dict[str, Any]]:
    rows = []
    for r in ev.runs:
        params = r.spec.detector.params()
        for p in r.pipes:
            a = r.attempts[p][0]
            loc = a.localization
            at = None if a.decision is None else a.decision.position
            first = (r.positions.get(p) or [PositionOutcome()])[0]
            region = None if a.decision is None else a.decision.region
            covered = (r.regions.get(p) or [RegionOutcome()])[0].covered
            rows.append(
                {
                    "detector": r.spec.detector.kind,
                    "mode": r.spec.mode.value,
                    "capture_interval": r.spec.capture_interval,
                    "threshold": params["threshold"],
                    "drift": params.get("drift", ""),
                    "sigma": params.get("sigma", ""),
                    "localization_interval": r.spec.localization_interval,
                    "pipe": p,
                    "true_start": r.truth[p][0],
                    "true_end": r.truth[p][1],
                    "predicted_start": a.predicted[0] if a.predicted else "",
                    "predicted_end": a.predicted[1] if a.predicted else "",
                    "correct": a.correct,
                    "time_to_localize_s": "" if not a.located else a.time_to_localize,
                    "rule": loc.rule.value if loc else "",
                    "trigger_node": loc.trigger_node if loc else "",
                    "phases_correct": sum(x.correct for x in r.attempts[p]),
                    "phases": len(r.offsets),
                    "position_m": "" if at is None else at.metres,
                    "position_from": "" if at is None else at.start,
                    "position_error_m": _blank(first.error),
                    "region_m": "" if region is None else region.length,
                    "region_pipes": "" if region is None else len(region.pipes),
                    "region_holds_burst": "" if not covered else covered[-1],
                }
            )
    return rows


def _blank(value: float | None) -> float | str:
    return "" if value is None else value


def write_csv(ev: Evaluation, path: str | os.PathLike[str]) -> Path:
    """Write one CSV row per run and pipe (phase 0, with the count of correct phases)."""
    text = io.StringIO(newline="")
    writer = csv.DictWriter(text, fieldnames=list(CSV_FIELDS))
    writer.writeheader()
    writer.writerows(_csv_rows(ev))
    return atomic.write_text(path, text.getvalue())
