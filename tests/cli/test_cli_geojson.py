"""`burstloc geojson`: the record a real monitor run printed, as GeoJSON a GIS library reads,
in WGS 84 from the network's EPSG; bad input named."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from burstloc.gis import record_geojson
from burstloc.layout import read_layout
from utm_network import CRS, feed_files

shapely = pytest.importorskip("shapely")
pytest.importorskip("pyproj")


def _burstloc(*argv: str, stdin: str | None = None) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "burstloc", *argv]
    return subprocess.run(command, input=stdin, capture_output=True, text=True, check=False)


@pytest.fixture(scope="module")
def monitored(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(network, the monitor's output) of a real burst replayed by `burstloc monitor`."""
    folder = tmp_path_factory.mktemp("geojson")
    network, config, feed = feed_files(folder)
    done = _burstloc(
        "monitor", str(network), "--config", str(config), "--capture-interval", "0.2",
        "--readings", str(feed), "--health-every", "30",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    out = folder / "out.jsonl"
    out.write_text(done.stdout)
    return network, out


def test_the_monitors_decision_as_wgs84_geojson(
    monitored: tuple[Path, Path], tmp_path: Path
) -> None:
    from shapely.geometry import shape

    network, out = monitored
    records = [json.loads(line) for line in out.read_text().splitlines()]
    decisions = [r for r in records if r["type"] == "decision"]
    assert len(decisions) == 1 and any(r["type"] == "health" for r in records)
    target = tmp_path / "region.geojson"
    done = _burstloc(
        "geojson", str(network), "--record", str(out), "--crs", CRS, "--out", str(target)
    )
    assert done.returncode == 0, done.stderr
    assert f"wrote {target}:" in done.stderr
    written = json.loads(target.read_text())
    expected = record_geojson(read_layout(network), decisions[0], crs=CRS)
    assert written == json.loads(json.dumps(expected))
    geometries = [shape(f["geometry"]) for f in written["features"]]
    assert all(g.is_valid for g in geometries)
    roles = [f["properties"]["role"] for f in written["features"]]
    assert roles.count("named_point") == 1 and roles.count("meter") == len(decisions[0]["meters"])
    assert all(14.9 < g.centroid.x < 15.1 and 44.9 < g.centroid.y < 45.1 for g in geometries)
    # stdin, the network's own coordinates
    piped = _burstloc("geojson", str(network), stdin=out.read_text())
    assert piped.returncode == 0, piped.stderr
    assert json.loads(piped.stdout) == json.loads(
        json.dumps(record_geojson(read_layout(network), decisions[0]))
    )


def test_bad_input_is_one_line_naming_it(
    monitored: tuple[Path, Path], tmp_path: Path, tiny: Path
) -> None:
    network, out = monitored
    health_only = tmp_path / "health.jsonl"
    health_only.write_text('{"type": "health", "time": 1.0}\n')
    cases = [
        (["--record", str(out), "--index", "2"], "--index 2: "),
        (["--record", str(health_only)], "no record with a region or a named point"),
        (["--record", str(tmp_path / "nope.jsonl")], "cannot read records"),
        (["--record", str(out), "--crs", "EPSG:99999"], "'EPSG:99999' is not a coordinate"),
        (["--record", str(out), "--out", str(tmp_path / "no" / "dir.json")], "no"),
    ]
    for options, text in cases:
        done = _burstloc("geojson", str(network), *options)
        assert done.returncode == 2, (options, done.stderr)
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("burstloc: error: ") and text in lines[0], (
            options, done.stderr,
        )  # fmt: skip
    other = _burstloc("geojson", str(tiny), "--record", str(out))  # another network's record
    assert other.returncode == 2 and "is not a pipe of the network" in other.stderr, other.stderr
