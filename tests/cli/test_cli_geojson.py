"""`burstloc geojson`: the record a real monitor run printed, as GeoJSON a GIS library reads,
in WGS 84 from the network's EPSG; bad input named."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from burstloc.gis import record_geojson
from burstloc.layout import read_layout
from utm_network import CRS, LV95, LV95_SHIFT, feed_files, utm_copy

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


def test_at_a_stated_epsg_the_geojson_opens_in_a_gis_library_where_the_network_is(
    monitored: tuple[Path, Path], tmp_path: Path
) -> None:
    """The same burst's record on a copy of the network drawn in the Swiss national grid
    (EPSG:2056: eastings in the millions), written with ``--crs EPSG:2056``, read back with
    shapely and pyproj: every coordinate returns to the network's within a metre, the place is
    Bern, and the named point lies on the search region's geometry."""
    import pyproj
    from shapely.geometry import LineString, Point, shape
    from shapely.ops import unary_union

    _, out = monitored
    network = utm_copy(tmp_path, LV95_SHIFT, "paper15_lv95.inp")
    target = tmp_path / "lv95.geojson"
    done = _burstloc(
        "geojson", str(network), "--record", str(out), "--crs", LV95, "--out", str(target)
    )
    assert done.returncode == 0, done.stderr
    written = json.loads(target.read_text())
    assert written["burstloc"]["coordinates"] == f"EPSG:4326 from {LV95}"
    back = pyproj.Transformer.from_crs("EPSG:4326", LV95, always_xy=True).transform

    def grid(geometry: Any) -> list[tuple[float, float]]:
        """The geometry's points back in the grid (pyproj), as read by shapely."""
        return [back(*c) for c in _coords(geometry)]

    layout = read_layout(network)
    records = [json.loads(line) for line in out.read_text().splitlines()]
    (record,) = [r for r in records if r["type"] == "decision"]
    local = record_geojson(layout, record)  # the network's own coordinates
    features = written["features"]
    assert len(features) == len(local["features"])
    worst = 0.0
    for there, here in zip(features, local["features"], strict=True):
        geometry = shape(there["geometry"])
        lon, lat = geometry.centroid.x, geometry.centroid.y
        assert 7.35 < lon < 7.55 and 46.9 < lat < 47.05  # Bern and its north (a 6 km drawing)
        for a, b in zip(grid(geometry), _coords(shape(here["geometry"])), strict=True):
            worst = max(worst, abs(a[0] - b[0]), abs(a[1] - b[1]))
    assert worst < 1.0  # metres
    meters = {f["properties"]["meter"]: f for f in features if f["properties"]["role"] == "meter"}
    for name, feature in meters.items():
        x, y = back(*feature["geometry"]["coordinates"])
        assert abs(x - layout.nodes[name][1]) < 1.0 and abs(y - layout.nodes[name][2]) < 1.0
    # the named point is on the region: within a metre of its stretches, in the grid's metres
    region = unary_union(
        [LineString(grid(shape(f["geometry"]))) for f in features
         if f["properties"]["role"] == "region"]
    )  # fmt: skip
    (named,) = [f for f in features if f["properties"]["role"] == "named_point"]
    point = Point(back(*named["geometry"]["coordinates"]))
    assert region.distance(point) < 1.0


def _coords(geometry: Any) -> list[tuple[float, float]]:
    return [(float(c[0]), float(c[1])) for c in geometry.coords]


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
