"""The robustness study's report (:mod:`burstloc.experiments.study`): ``report.md`` (top-1 /
top-3 per capture interval, the summary first), ``results.json`` and the plots, written
atomically (:mod:`burstloc._atomic`)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from burstloc import _atomic as atomic
from burstloc.constants import WAVE_SPEED
from burstloc.experiments.report import pct

if TYPE_CHECKING:
    from burstloc.experiments.grid import StudySettings

__all__ = ["write_study_report"]


def _study_table(
    rows: Sequence[Mapping[str, Any]], intervals: Sequence[float], label_keys: Sequence[str]
) -> str:
    """Top-1 / top-3 % per capture interval (columns), one line per value of ``label_keys``."""
    head = "| " + " | ".join(label_keys) + " | "
    head += " | ".join(f"{dt:g} s" for dt in intervals) + " |"
    lines = [head, "|" + "---|" * (len(label_keys) + len(intervals))]
    groups: dict[tuple[Any, ...], dict[float, Mapping[str, Any]]] = {}
    for row in rows:
        groups.setdefault(tuple(row[k] for k in label_keys), {})[row["capture_interval"]] = row
    for key, by_dt in groups.items():
        cells = []
        for dt in intervals:
            r = by_dt.get(dt)
            cells.append("-" if r is None else f"{pct(r['top1'], '')} / {pct(r['top3'], '')}")
        lines.append("| " + " | ".join(str(k) for k in key) + " | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def write_study_report(
    rows: list[dict[str, Any]],
    settings: StudySettings,
    out_dir: str | os.PathLike[str],
    problems: Sequence[str] = (),
) -> Path:
    """Write ``report.md``, ``results.json`` and the PNG plots to ``out_dir``; return the report.

    The report's first table is the summary (fused localizer, CUSUM detector, both meter
    models: top-1 / top-3 % per capture interval for every grid point); then the defaults of
    every network per detector and localizer; then every row.
    """
    from burstloc.experiments.plot import plot_accuracy_by_interval

    out = Path(out_dir)
    document = {"settings": settings.to_json(), "rows": rows, "problems": list(problems)}
    atomic.write_json(out / "results.json", document)
    dts = list(settings.capture_intervals)
    parts = [
        "# burstloc robustness study",
        "",
        f"Top-1 / top-3 accuracy (%) over {settings.phases} phases of the capture clock; "
        "calibrated detectors (no hand tuning); one factor varied at a time around the "
        "defaults (noise-free meters on every junction, burst at mid-pipe, coefficient 0.01, "
        "TSNet steady friction). See `burstloc.experiments.study` for the rules.",
        "",
    ]
    speeds = settings.wave_speeds
    if speeds:
        parts += [
            f"Wave speeds per pipe{f' from {speeds.source}' if speeds.source else ''}: "
            f"{len(speeds.pipes)} pipe(s) and {len(speeds.diameters)} diameter class(es) of "
            f"their own speed, the others at {WAVE_SPEED:g} m/s; the bursts are simulated, the "
            "meters placed and the localizers calibrated with them.",
            "",
        ]
    if problems:
        parts += ["**Left out:**", "", *[f"- {p}" for p in problems], ""]
    best = settings.localizers[-1] if "fused" not in settings.localizers else "fused"
    det = settings.detectors[0]
    summary = [r for r in rows if r["localizer"] == best and r["detector"] == det]
    parts += [f"## Summary ({best} localizer, {det})", ""]
    parts += [_study_table(summary, dts, ["point", "meters", "meter_model"]), ""]
    parts += ["## Every network at the defaults", ""]
    defaults = [r for r in rows if r["factor"] == "default"]
    parts += [_study_table(defaults, dts, ["network", "detector", "localizer", "meter_model"]), ""]
    times = [
        r for r in defaults if r["capture_interval"] == min(dts) and r["median_time_s"] is not None
    ]
    if times:
        parts += [f"Median time from burst to decision at {min(dts):g} s:", ""]
        parts += [
            f"- {r['network']} {r['detector']} {r['localizer']} {r['meter_model']}: "
            f"{r['median_time_s']:.2f} s"
            for r in times
        ]
        parts.append("")
    parts += ["## All rows", ""]
    parts += [_study_table(rows, dts, ["point", "detector", "localizer", "meter_model"]), ""]
    for network in dict.fromkeys(r["network"] for r in rows):
        sub = [r for r in defaults if r["network"] == network]
        name = f"{network}_defaults.png"
        plot_accuracy_by_interval(sub, out / name, f"{network} defaults", ["detector", "localizer"])
        parts.append(f"![{network}]({name})")
    for factor in dict.fromkeys(r["factor"] for r in rows if r["factor"] != "default"):
        sub = [
            r
            for r in rows
            if r["localizer"] == best
            and r["detector"] == det
            and (
                r["factor"] == factor
                or (r["factor"] == "default" and r["network"] == rows[0]["network"])
            )
        ]
        name = f"factor_{factor}.png"
        plot_accuracy_by_interval(sub, out / name, f"{factor} ({best}, {det})", ["point"])
        parts.append(f"![{factor}]({name})")
    return atomic.write_text(out / "report.md", "\n".join(parts) + "\n")
