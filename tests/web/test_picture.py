"""``burstloc incidents png``: a real burst kept by a real ``burstloc monitor --db`` run, drawn by
headless Chromium (Debian's) from the page's snapshot view, and the PNG read back by hand."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from png_pixels import count_colour, read_png
from test_control_room import PAPER15, config, feed  # noqa: F401 (fixtures)
from web_browser import CHROMIUM

from burstloc.localize.config import Calibration

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="needs Chromium: apt-get install chromium")

REGION = (0xFF, 0xD2, 0x3F)  # the page's COLORS.region
NAMED = (0xFF, 0x2D, 0x55)  # COLORS.named


def _burstloc(*argv: str) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "burstloc", *argv]
    return subprocess.run(command, capture_output=True, text=True, check=False, timeout=600)


@pytest.fixture(scope="module")
def kept(
    config: tuple[Calibration, Path],  # noqa: F811
    feed: list[str],  # noqa: F811
    tmp_path_factory: pytest.TempPathFactory,
) -> tuple[Path, int, dict]:
    """(store, the burst's incident id, its record) of a real monitor run over a real burst."""
    from burstloc.incidents.store import IncidentStore

    folder = tmp_path_factory.mktemp("picture")
    readings = folder / "feed.csv"
    readings.write_text("\n".join(feed) + "\n")
    db = folder / "incidents.sqlite"
    done = _burstloc(
        "monitor", str(PAPER15), "--config", str(config[1]), "--capture-interval", "0.2",
        "--readings", str(readings), "--db", str(db),
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    store = IncidentStore.open(str(db))
    try:
        (burst,) = [r for r in store.incidents() if r["kind"] == "burst"]
        record = store.get(burst["id"])["record"]
    finally:
        store.close()
    return db, burst["id"], record


def test_an_incident_as_a_png_of_the_size_asked_with_its_region_and_named_pipe(
    kept: tuple[Path, int, dict], tmp_path: Path
) -> None:
    db, incident, record = kept
    assert record["type"] == "decision" and record["region"]["stretches"]
    out = tmp_path / "work-order.png"
    done = _burstloc(
        "incidents", "png", str(incident), "--db", str(db), "--network", str(PAPER15),
        "--out", str(out), "--size", "900x600",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert f"wrote {out}: incident {incident}, 900x600" in done.stderr
    width, height, rows = read_png(out.read_bytes())
    assert (width, height) == (900, 600)
    # the region (yellow) and the named pipe above it (red) are on the picture
    assert count_colour(rows, REGION) > 200
    assert count_colour(rows, NAMED) > 50


def test_a_picture_of_what_cannot_be_drawn_is_refused_by_name(
    kept: tuple[Path, int, dict], tmp_path: Path, tiny: Path
) -> None:
    db, incident, _ = kept
    out = str(tmp_path / "x.png")
    cases = [
        (["999", "--network", str(PAPER15)], "999"),
        ([str(incident), "--network", str(tiny)], "is not a pipe of the network"),
        ([str(incident), "--network", str(PAPER15), "--size", "12x9"], "--size wants WIDTHxHEIGHT"),
    ]
    for argv, text in cases:
        done = _burstloc("incidents", "png", *argv, "--db", str(db), "--out", out)
        assert done.returncode == 2, (argv, done.stderr)
        assert text in done.stderr and done.stderr.count("\n") == 1, (argv, done.stderr)
    assert not Path(out).exists()
