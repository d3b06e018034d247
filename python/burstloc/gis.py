"""A located burst on the crew's map: a record's search region, named point and meters as GeoJSON.

:func:`record_geojson` turns a monitor record (``"type"``: decision, transient or event; see
the README's monitor section) into a GeoJSON ``FeatureCollection`` (RFC 7946) drawn on the
network's layout (:mod:`burstloc.layout`):

* each **stretch of the search region** is a ``LineString`` (``"role": "region"``): the part of
  its pipe's drawing from ``low`` to ``high`` metres from the stretch's ``from`` node, with the
  stretch's probability and the probability that the burst is on that pipe;
* the **named point** (the record's ``position``) is a ``Point`` (``"role": "named_point"``) and
  its interval ``low``..``high`` on the pipe a ``LineString`` (``"role": "position_range"``);
* each **meter** of the record is a ``Point`` (``"role": "meter"``) with whether it alarmed and
  whether it was excluded (silent).

A distance along a pipe is placed on the pipe's drawing (its end nodes' coordinates and its
vertices) in proportion to the pipe's length in the INP file: metres 150 of a 600 m pipe lie a
quarter of the way along its drawn line, whatever the drawing's scale.

Coordinates are the INP file's ``[COORDINATES]`` and ``[VERTICES]`` as they are, or, with a
``crs`` (``"EPSG:32633"``, anything :class:`pyproj.CRS` reads), transformed to WGS 84
longitude, latitude as RFC 7946 wants them (needs ``pyproj``: ``pip install 'burstloc[gis]'``).
The collection's foreign member ``"burstloc"`` says which, and summarizes the record.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

from burstloc._validate import Fields, check_number, check_string
from burstloc.exceptions import ConfigError
from burstloc.layout import Layout, drawn_lengths

__all__ = ["ROUNDING", "WGS84", "located_records", "record_geojson", "to_wgs84"]

#: The coordinate reference system of RFC 7946 GeoJSON: WGS 84, longitude then latitude.
WGS84 = "EPSG:4326"

Point = tuple[float, float]

#: The most stretches, pipes or meters a record is read with (far above any record's).
_MOST = 1_000_000

#: Metres a stretch's ends may pass its pipe's: records write them to 0.1 m
#: (:meth:`burstloc.localize.region.Stretch.to_json`), so a stretch to the end of a 51.5963 m
#: pipe says ``"high": 51.6``. Within this, an end is taken as the pipe's; beyond, refused.
ROUNDING = 0.05


def record_geojson(
    layout: Layout, record: Any, *, crs: str | None = None, source: str = "the record"
) -> dict[str, Any]:
    """The GeoJSON ``FeatureCollection`` of ``record`` on ``layout`` (module docstring); with
    ``crs``, the network's coordinate system, transformed to WGS 84.

    Raises:
        ConfigError: the record is not a monitor record with a region or a named point, names
            a pipe, node or meter that is not in the network (``source`` names the record in
            the message), ``crs`` is unknown, or pyproj is missing.
    """
    fields = Fields(record, source)
    kind = check_string(fields.get("type"), "type")
    features: list[dict[str, Any]] = []
    with fields.checking():
        if "region" in fields.data and fields.data["region"] is not None:
            features += _region(layout, fields.obj("region"))
        if "position" in fields.data and fields.data["position"] is not None:
            features += _named_point(layout, fields.obj("position"))
        if not features:
            raise ConfigError(
                f"{source}: a {kind!r} record without a region or a named point (position): "
                "nothing to draw"
            )
        alarmed = set(_names(fields.data.get("alarmed", []), "alarmed"))
        excluded = set(_names(fields.data.get("excluded", []), "excluded"))
        for meter in _names(fields.data.get("meters", []), "meters"):
            if meter not in layout.nodes:
                raise ConfigError(f"meter {meter!r} is not a node of the network")
            _, x, y = layout.nodes[meter]
            features.append(
                _feature(
                    {"type": "Point", "coordinates": [x, y]},
                    role="meter",
                    meter=meter,
                    alarmed=meter in alarmed,
                    excluded=meter in excluded,
                )
            )
    collection = {
        "type": "FeatureCollection",
        "features": features,
        "burstloc": _summary(fields.data, kind),
    }
    if crs is not None:
        collection = to_wgs84(collection, crs)
    return collection


def to_wgs84(collection: dict[str, Any], crs: str) -> dict[str, Any]:
    """``collection`` (in the coordinate system ``crs``) with every coordinate transformed to
    WGS 84 longitude, latitude (a new collection; ``collection`` is left as it is).

    Raises:
        ConfigError: pyproj is missing, ``crs`` is not a coordinate system pyproj knows, or a
            coordinate does not transform to a longitude and latitude (the network is not
            drawn in ``crs``).
    """
    try:
        from pyproj import CRS, Transformer
        from pyproj.exceptions import CRSError
    except ImportError:
        raise ConfigError(
            "--crs needs pyproj: pip install 'burstloc[gis]' (or write the network's own "
            "coordinates: leave out --crs)"
        ) from None
    try:
        source = CRS.from_user_input(crs)
    except CRSError as exc:
        raise ConfigError(f"--crs {crs!r} is not a coordinate reference system: {exc}") from None
    transformer = Transformer.from_crs(source, WGS84, always_xy=True)
    out = {**collection, "features": []}
    for feature in collection["features"]:
        geometry = feature["geometry"]
        coordinates = geometry["coordinates"]
        points = [coordinates] if geometry["type"] == "Point" else coordinates
        xs, ys = transformer.transform([p[0] for p in points], [p[1] for p in points])
        moved = [[float(x), float(y)] for x, y in zip(xs, ys, strict=True)]
        if not all(math.isfinite(x) and abs(x) <= 180 and abs(y) <= 90 for x, y in moved):
            raise ConfigError(
                f"the network's coordinates {points[0]} do not transform from {crs} to WGS 84: "
                f"is the network drawn in {crs}?"
            )
        shape = moved[0] if geometry["type"] == "Point" else moved
        out["features"].append({**feature, "geometry": {**geometry, "coordinates": shape}})
    out["burstloc"] = {**collection.get("burstloc", {}), "coordinates": f"{WGS84} from {crs}"}
    return out


def located_records(text: str, source: str) -> list[tuple[str, dict[str, Any]]]:
    """The records of ``text`` (the monitor's output: JSON lines; or one JSON record, over
    several lines) that locate something (a ``region`` or a ``position``), as (where, record),
    ``where`` naming the line of ``source``.

    Raises:
        ConfigError: a line that is not JSON (naming ``source`` and the line).
    """
    try:
        whole = json.loads(text)
    except ValueError:
        whole = None
    if isinstance(whole, dict):
        documents = [(source, whole)]
    else:
        documents = []
        for number, line in enumerate(text.splitlines(), start=1):
            if not line.strip():
                continue
            where = f"{source}, line {number}"
            try:
                documents.append((where, json.loads(line)))
            except ValueError as exc:
                raise ConfigError(f"{where}: not a JSON record: {exc}") from None
    return [
        (where, doc)
        for where, doc in documents
        if isinstance(doc, dict) and (doc.get("region") or doc.get("position"))
    ]


# ---------------------------------------------------------------------- the parts
def _names(values: Any, field: str) -> list[str]:
    if not isinstance(values, list) or not all(isinstance(v, str) for v in values):
        raise ConfigError(f"{field} must be a list of meter names")
    return list(values)


def _summary(record: Mapping[str, Any], kind: str) -> dict[str, Any]:
    region = record.get("region") or {}
    pipes = record.get("pipes") or []
    best = pipes[0].get("pipe") if pipes and isinstance(pipes[0], dict) else None
    return {
        "record": kind,
        "time": record.get("time"),
        "first_alarm": record.get("first_alarm"),
        "pipe": best,
        "confidence": region.get("confidence"),
        "region_length_m": region.get("length_m"),
        "coordinates": "the network's (its INP file's [COORDINATES] and [VERTICES])",
    }


def _region(layout: Layout, region: Fields) -> list[dict[str, Any]]:
    on_pipe: dict[str, float] = {}
    if "pipes" in region.data:
        for item in region.objects("pipes", high=_MOST):
            with item.checking():
                pipe = check_string(item.get("pipe"), "pipe")
                on_pipe[pipe] = check_number(item.get("probability"), "probability", low=0, high=1)
    features = []
    for rank, stretch in enumerate(region.objects("stretches", high=_MOST), start=1):
        with stretch.checking():
            pipe, start, line = _pipe(layout, stretch)
            length = layout.lengths[pipe]
            low = check_number(stretch.get("low"), "low", low=0, high=length + ROUNDING)
            high = check_number(stretch.get("high"), "high", low=low, high=length + ROUNDING)
            low, high = min(low, length), min(high, length)
            probability = check_number(stretch.get("probability"), "probability", low=0, high=1)
        features.append(
            _feature(
                {"type": "LineString", "coordinates": _cut(line, low / length, high / length)},
                role="region",
                rank=rank,
                pipe=pipe,
                **{"from": start},
                low_m=low,
                high_m=high,
                probability=probability,
                pipe_probability=on_pipe.get(pipe),
            )
        )
    return features


def _named_point(layout: Layout, position: Fields) -> list[dict[str, Any]]:
    with position.checking():
        pipe, start, line = _pipe(layout, position)
        length = layout.lengths[pipe]
        metres = check_number(position.get("metres"), "metres", low=0, high=length)
        low = check_number(position.data.get("low", metres), "low", low=0, high=metres)
        high = check_number(position.data.get("high", metres), "high", low=metres, high=length)
    where = {"pipe": pipe, "from": start, "length_m": length}
    return [
        _feature(
            {"type": "Point", "coordinates": list(_at(line, metres / length))},
            role="named_point",
            metres=metres,
            **where,
        ),
        _feature(
            {"type": "LineString", "coordinates": _cut(line, low / length, high / length)},
            role="position_range",
            low_m=low,
            high_m=high,
            **where,
        ),
    ]


def _pipe(layout: Layout, fields: Fields) -> tuple[str, str, list[Point]]:
    """(pipe, its ``from`` node, its drawing from that node) of a stretch or position."""
    pipe = check_string(fields.get("pipe"), "pipe")
    start = check_string(fields.get("from"), "from")
    if pipe not in layout.lengths:
        raise ConfigError(f"pipe {pipe!r} is not a pipe of the network (another network's record?)")
    _, a, b, _ = layout.links[pipe]
    if start not in (a, b):
        raise ConfigError(f"node {start!r} is not an end of pipe {pipe!r} ({a!r}, {b!r})")
    if layout.lengths[pipe] <= 0:
        raise ConfigError(f"pipe {pipe!r} has no length in the network file")
    line = layout.line(pipe)
    return pipe, start, line if start == a else line[::-1]


def _feature(geometry: dict[str, Any], **properties: Any) -> dict[str, Any]:
    return {"type": "Feature", "geometry": geometry, "properties": properties}


def _at(line: Sequence[Point], fraction: float) -> Point:
    """The point ``fraction`` (0..1) of the way along ``line``'s drawn length."""
    along = drawn_lengths(line)
    target = min(max(fraction, 0.0), 1.0) * along[-1]
    for k in range(1, len(line)):
        if along[k] >= target and along[k] > along[k - 1]:
            t = (target - along[k - 1]) / (along[k] - along[k - 1])
            (x0, y0), (x1, y1) = line[k - 1], line[k]
            return (x0 + t * (x1 - x0), y0 + t * (y1 - y0))
    return line[-1] if fraction > 0 else line[0]


def _cut(line: Sequence[Point], low: float, high: float) -> list[list[float]]:
    """The part of ``line`` from ``low`` to ``high`` (fractions of its drawn length), as GeoJSON
    positions: its two ends and the vertices between (two equal points for an empty part)."""
    along = drawn_lengths(line)
    total = along[-1]
    inner: Iterable[Point] = (
        p for p, d in zip(line, along, strict=True) if low * total < d < high * total
    )
    return [list(p) for p in (_at(line, low), *inner, _at(line, high))]
