"""What the page's server gives other systems: ``/metrics`` for the utility's monitoring
(Prometheus' text format, :mod:`burstloc.web.metrics`) and ``/region.geojson`` for its GIS (the
current record's search region, named point and meters, :mod:`burstloc.gis`).

Both are GET routes under the page's access rules (the token, when there is one, as
``Authorization: Bearer`` for a scraper, or the page's cookie for the download link). Each is
answered from what the server holds (:attr:`WebServer.metrics`, :attr:`WebServer.region`, set
once the monitor's loop exists); before that, 503 (the monitor is starting).
"""

from __future__ import annotations

import json
from typing import Any

from burstloc.exceptions import ConfigError
from burstloc.gis import record_geojson, to_wgs84
from burstloc.layout import Layout

__all__ = ["GEOJSON_TYPE", "RegionExport", "routes"]

_STARTING = "not ready: the monitor is starting"

#: GeoJSON's media type (RFC 7946).
GEOJSON_TYPE = "application/geo+json"


class RegionExport:
    """The current record as GeoJSON on ``layout``: in the network's coordinates, or with
    ``crs`` (the network's coordinate system) in WGS 84.

    Raises:
        ConfigError: ``crs`` is not a coordinate system, or pyproj is missing.
    """

    def __init__(self, layout: Layout, crs: str | None = None) -> None:
        self.layout = layout
        self.crs = crs
        self.check_crs(crs)

    @staticmethod
    def check_crs(crs: str | None) -> None:
        """Refuse a ``crs`` pyproj does not know (or any, without pyproj).

        Raises:
            ConfigError: as the constructor.
        """
        if crs is not None:
            to_wgs84({"type": "FeatureCollection", "features": []}, crs)

    def of(self, record: dict[str, Any]) -> dict[str, Any]:
        """``record`` as a FeatureCollection (:func:`burstloc.gis.record_geojson`).

        Raises:
            ConfigError: the record has no region or named point, or is of another network.
        """
        return record_geojson(self.layout, record, crs=self.crs, source="the current record")


def _current(view: Any) -> dict[str, Any] | None:
    """The incident's answer (decision or event) when it locates something, else its early
    record (``None``: nothing located yet)."""
    for record in (view.answer, view.transient):
        if record is not None and (record.get("region") or record.get("position")):
            return dict(record)
    return None


def routes(server: Any) -> list[Any]:
    """The ``/metrics`` and ``/region.geojson`` routes of ``server`` (a
    :class:`~burstloc.web.server.WebServer`)."""
    from starlette.responses import PlainTextResponse, Response
    from starlette.routing import Route

    async def metrics(request: Any) -> Any:
        if server.metrics is None:
            return PlainTextResponse(_STARTING, status_code=503)
        try:
            body = server.metrics.exposition()
        except ImportError:
            text = "metrics need prometheus_client: pip install 'burstloc[web]'"
            return PlainTextResponse(text, status_code=501)
        from burstloc.web.metrics import CONTENT_TYPE

        return Response(body, media_type=CONTENT_TYPE)

    async def region(request: Any) -> Any:
        if server.region is None:
            return PlainTextResponse(_STARTING, status_code=503)
        record = _current(server.view)
        if record is None:
            return PlainTextResponse("nothing located yet: no region to export", status_code=404)
        try:
            document = server.region.of(record)
        except ConfigError as exc:
            return PlainTextResponse(f"the current record cannot be drawn: {exc}", 500)
        name = f"burstloc-{record['type']}-{record.get('time', 0):g}s.geojson"
        return Response(
            json.dumps(document, separators=(",", ":")).encode(),
            media_type=GEOJSON_TYPE,
            headers={"Content-Disposition": f'attachment; filename="{name}"'},
        )

    return [Route("/metrics", metrics), Route("/region.geojson", region)]
