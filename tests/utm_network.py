"""The shipped paper15 network drawn in real map coordinates (UTM zone 33N, EPSG:32633; or the
Swiss national grid, EPSG:2056), and a real decision record on it: a TSNet burst replayed
through the live loop. A record names pipes and nodes, not coordinates: one record is good on
every copy."""

from __future__ import annotations

from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
PAPER15 = REPO / "networks" / "paper15.inp"

#: The coordinate system the copy is drawn in, and the shift of paper15's drawing into it:
#: about 15 deg E, 45 deg N (a town in zone 33N's central strip).
CRS = "EPSG:32633"
SHIFT = (497_000.0, 4_978_000.0)
#: A second projected system, with false eastings in the millions: the Swiss LV95 grid, the
#: drawing shifted to its origin (Bern, about 7.44 deg E, 46.95 deg N).
LV95 = "EPSG:2056"
LV95_SHIFT = (2_600_000.0, 1_200_000.0)
METERS = ("N3", "N5", "N8", "2", "4", "6", "8")
BURST_PIPE = "9"


def utm_copy(
    folder: Path, shift: tuple[float, float] = SHIFT, name: str = "paper15_utm.inp"
) -> Path:
    """paper15.inp with every coordinate and vertex shifted by ``shift`` (default
    :data:`SHIFT`; the hydraulics unchanged), written in ``folder`` as ``name``."""
    lines, section = [], ""
    for line in PAPER15.read_text().splitlines():
        stripped = line.strip()
        if stripped.startswith("["):
            section = stripped.upper()
        elif section in ("[COORDINATES]", "[VERTICES]") and stripped and stripped[0] != ";":
            node, x, y, *_ = stripped.split()
            line = f" {node}\t{float(x) + shift[0]:.3f}\t{float(y) + shift[1]:.3f}"
        lines.append(line)
    out = folder / name
    out.write_text("\n".join(lines) + "\n")
    return out


def burst(network: Path) -> tuple[Any, list[Any]]:
    """The calibration for :data:`METERS` on ``network`` and the steps of a real TSNet burst of
    :data:`BURST_PIPE`: 60 s steady, the burst, 200 s after."""
    import sys

    sys.path.insert(0, str(REPO / "tests" / "live"))
    from live_feed import burst_steps

    from burstloc.experiments.calibrate import calibrate

    calibration = calibrate(network, capture_intervals=(0.2,), noise_sigma=0.01, meters=METERS)
    steps = burst_steps(network, calibration.meters, BURST_PIPE, sigma=0.003, after=200.0)
    return calibration, steps


def feed_files(folder: Path) -> tuple[Path, Path, Path]:
    """(network, configuration, readings CSV) of the burst in ``folder``, for a monitor."""
    network = utm_copy(folder)
    calibration, steps = burst(network)
    config = calibration.save(folder / "paper15_utm.json")
    lines = [
        f"{s.timestamp:.1f},{m},{float(v):.4f}"
        for s in steps
        for m, v in zip(calibration.meters, s.values, strict=True)
    ]
    feed = folder / "feed.csv"
    feed.write_text("\n".join(lines) + "\n")
    return network, config, feed


def decision_record(network: Path) -> dict[str, Any]:
    """The first decision of the live loop on :func:`burst`'s readings."""
    import sys

    sys.path.insert(0, str(REPO / "tests" / "live"))  # run alone, before burst() puts it there
    from live_feed import Collected, readings

    from burstloc.live.monitor import BurstMonitor

    calibration, steps = burst(network)
    run = Collected(BurstMonitor(network, calibration, capture_interval=0.2))
    run.run(readings(steps, calibration.meters))
    return run.decisions[0]
