"""burstloc.gis: a real decision record's region, named point and meters as GeoJSON, read back
with shapely and checked where they land, in the network's coordinates and in WGS 84 from a
known EPSG (pyproj)."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import pytest

from burstloc.exceptions import ConfigError
from burstloc.gis import located_records, record_geojson
from burstloc.layout import Layout, read_layout
from utm_network import CRS, SHIFT, decision_record, utm_copy

shapely = pytest.importorskip("shapely")
pyproj = pytest.importorskip("pyproj")
from shapely.geometry import LineString, Point, shape  # noqa: E402


@pytest.fixture(scope="module")
def setting(tmp_path_factory: pytest.TempPathFactory) -> tuple[Layout, dict[str, Any]]:
    network = utm_copy(tmp_path_factory.mktemp("utm"))
    record = decision_record(network)
    return read_layout(network), record


def _pipe_line(layout: Layout, pipe: str, start: str) -> LineString:
    _, a, b, vertices = layout.links[pipe]
    points = [layout.nodes[a][1:], *vertices, layout.nodes[b][1:]]
    return LineString(points if start == a else points[::-1])


def _by_role(collection: dict[str, Any], role: str) -> list[dict[str, Any]]:
    return [f for f in collection["features"] if f["properties"]["role"] == role]


def test_the_named_point_stretches_and_meters_land_on_their_pipes_and_nodes(
    setting: tuple[Layout, dict[str, Any]],
) -> None:
    layout, record = setting
    collection = record_geojson(layout, record)
    assert collection["type"] == "FeatureCollection"
    for feature in collection["features"]:
        assert shape(feature["geometry"]).is_valid
    position = record["position"]
    (named,) = _by_role(collection, "named_point")
    line = _pipe_line(layout, position["pipe"], position["from"])
    point = shape(named["geometry"])
    assert line.distance(point) < 1e-6
    assert line.project(point, normalized=True) == pytest.approx(
        position["metres"] / position["length"], abs=1e-9
    )
    (span,) = _by_role(collection, "position_range")
    start, end = (
        Point(c)
        for c in span["geometry"]["coordinates"][:: len(span["geometry"]["coordinates"]) - 1]
    )
    assert line.project(start, normalized=True) == pytest.approx(
        position["low"] / position["length"]
    )
    assert line.project(end, normalized=True) == pytest.approx(
        position["high"] / position["length"]
    )

    stretches = _by_role(collection, "region")
    assert len(stretches) == len(record["region"]["stretches"])
    for feature, stretch in zip(stretches, record["region"]["stretches"], strict=True):
        props = feature["properties"]
        assert (props["pipe"], props["from"], props["probability"]) == (
            stretch["pipe"], stretch["from"], stretch["probability"],
        )  # fmt: skip
        pipe_line = _pipe_line(layout, stretch["pipe"], stretch["from"])
        drawn = shape(feature["geometry"])
        assert pipe_line.buffer(1e-6).contains(drawn)
        length = layout.lengths[stretch["pipe"]]
        assert drawn.length == pytest.approx(
            pipe_line.length * (stretch["high"] - stretch["low"]) / length, rel=1e-9
        )
    assert sum(f["properties"]["probability"] for f in stretches) == pytest.approx(
        record["region"]["probability"], abs=1e-3
    )
    meters = {f["properties"]["meter"]: f for f in _by_role(collection, "meter")}
    assert list(meters) == record["meters"]
    for name, feature in meters.items():
        assert tuple(feature["geometry"]["coordinates"]) == layout.nodes[name][1:]
        assert feature["properties"]["alarmed"] == (name in record["alarmed"])
    assert collection["burstloc"]["pipe"] == record["pipes"][0]["pipe"]


def test_wgs84_from_a_known_epsg_is_where_pyproj_and_the_geodesic_put_it(
    setting: tuple[Layout, dict[str, Any]],
) -> None:
    layout, record = setting
    local = record_geojson(layout, record)
    world = record_geojson(layout, record, crs=CRS)
    assert world["burstloc"]["coordinates"] == f"EPSG:4326 from {CRS}"
    forward = pyproj.Transformer.from_crs(CRS, "EPSG:4326", always_xy=True)
    back = pyproj.Transformer.from_crs("EPSG:4326", CRS, always_xy=True)
    for here, there in zip(local["features"], world["features"], strict=True):
        assert here["properties"] == there["properties"]
        ours = shape(there["geometry"])
        theirs = shape(here["geometry"])
        for (x, y), (lon, lat) in zip(_points(theirs), _points(ours), strict=True):
            assert (lon, lat) == pytest.approx(forward.transform(x, y), abs=1e-12)
            assert back.transform(lon, lat) == pytest.approx((x, y), abs=1e-3)  # 1 mm
            assert 14.9 < lon < 15.1 and 44.9 < lat < 45.1  # zone 33N's centre, 45 deg N
    # metres on the ground: the geodesic between two meters equals their distance on the
    # drawing within UTM's scale factor (0.9996 on the central meridian)
    geod = pyproj.Geod(ellps="WGS84")
    meters = {f["properties"]["meter"]: f["geometry"]["coordinates"] for f in world["features"]
              if f["properties"]["role"] == "meter"}  # fmt: skip
    a, b = record["meters"][0], record["meters"][-1]
    ground = geod.inv(*meters[a], *meters[b])[2]
    drawn = math.dist(layout.nodes[a][1:], layout.nodes[b][1:])
    assert drawn > 500 and 0.9990 < drawn / ground < 1.0002
    # and the named point is where paper15's own drawing has it, shifted into the zone
    (named,) = _by_role(world, "named_point")
    x, y = back.transform(*named["geometry"]["coordinates"])
    original = read_layout(Path(__file__).resolve().parents[1] / "networks" / "paper15.inp")
    position = record["position"]
    unshifted = _pipe_line(original, position["pipe"], position["from"]).interpolate(
        position["metres"] / position["length"], normalized=True
    )
    assert (x - SHIFT[0], y - SHIFT[1]) == pytest.approx((unshifted.x, unshifted.y), abs=1e-3)


def _points(geometry: Any) -> list[tuple[float, float]]:
    return [tuple(c) for c in geometry.coords]


def test_a_record_of_another_network_or_without_a_place_is_refused_by_name(
    setting: tuple[Layout, dict[str, Any]],
) -> None:
    layout, record = setting
    foreign = copy.deepcopy(record)
    foreign["region"]["stretches"][2]["pipe"] = "P99"
    with pytest.raises(ConfigError, match=r"rec\.json: .*pipe 'P99' is not a pipe of the network"):
        record_geojson(layout, foreign, source="rec.json")
    wrong_end = copy.deepcopy(record)
    wrong_end["position"]["from"] = "N8"
    with pytest.raises(ConfigError, match=r"position: node 'N8' is not an end of pipe '9'"):
        record_geojson(layout, wrong_end)
    beyond = copy.deepcopy(record)
    beyond["position"]["metres"] = 5000.0
    with pytest.raises(ConfigError, match=r"position\.metres must be a finite number"):
        record_geojson(layout, beyond)
    with pytest.raises(ConfigError, match="without a region or a named point"):
        record_geojson(layout, {"type": "health", "time": 3.0})
    with pytest.raises(ConfigError, match="'EPSG:99999' is not a coordinate reference system"):
        record_geojson(layout, record, crs="EPSG:99999")
    # a drawing in metres is not longitude and latitude: said, not written as infinities
    with pytest.raises(ConfigError, match="do not transform from EPSG:4326"):
        record_geojson(layout, record, crs="EPSG:4326")


def test_a_stretch_rounded_past_its_pipes_end_ends_there(
    setting: tuple[Layout, dict[str, Any]], tmp_path: Path
) -> None:
    """Records write a stretch's ends to 0.1 m: on a pipe of 51.5963 m (L-TOWN has such) a
    stretch to its end says 51.6. It is drawn to the pipe's end; beyond the rounding, refused."""
    from burstloc.gis import ROUNDING

    layout, record = setting
    stretch = record["region"]["stretches"][0]
    length = layout.lengths[stretch["pipe"]]
    odd = tmp_path / "odd.inp"  # the same network with that pipe 0.04 m shorter
    text = utm_copy(tmp_path).read_text().splitlines()
    section = ""
    for k, line in enumerate(text):
        if line.strip().startswith("["):
            section = line.strip().upper()
        elif section == "[PIPES]" and line.split() and line.split()[0] == stretch["pipe"]:
            fields = line.split()
            fields[3] = f"{length - 0.04:.4f}"
            text[k] = " " + "\t".join(fields)
    odd.write_text("\n".join(text) + "\n")
    short = read_layout(odd)
    assert short.lengths[stretch["pipe"]] == pytest.approx(length - 0.04)
    rounded = copy.deepcopy(record)
    rounded["region"]["stretches"][0].update(low=0.0, high=length)  # 0.04 m past the end
    (drawn, *_) = _by_role(record_geojson(short, rounded), "region")
    assert drawn["properties"]["high_m"] == short.lengths[stretch["pipe"]]
    assert shape(drawn["geometry"]).length == pytest.approx(
        _pipe_line(short, stretch["pipe"], stretch["from"]).length
    )
    rounded["region"]["stretches"][0]["high"] = length - 0.04 + 2 * ROUNDING
    with pytest.raises(ConfigError, match=r"stretches\[0\]\.high must be a finite number"):
        record_geojson(short, rounded)


def test_located_records_of_the_monitors_output() -> None:
    lines = '{"type": "health", "time": 1}\n\n{"type": "decision", "position": {"pipe": "9"}}\n'
    assert located_records(lines, "out.jsonl") == [
        ("out.jsonl, line 3", {"type": "decision", "position": {"pipe": "9"}})
    ]
    one = '{\n "type": "transient",\n "region": {"stretches": []}\n}\n'
    assert located_records(one, "rec.json")[0][0] == "rec.json"
    with pytest.raises(ConfigError, match=r"out\.jsonl, line 2: not a JSON record"):
        located_records('{"type": "health"}\n{oops\n', "out.jsonl")
