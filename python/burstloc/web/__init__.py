"""The control room: a live web view of the running monitor (``burstloc monitor --web``).

A thin layer beside :mod:`burstloc.live`: :class:`~burstloc.web.hub.Hub` is the live loop's
observer (the monitor only appends to its bounded inbox and never waits),
:class:`~burstloc.web.view.View` keeps the state a page is shown first,
:class:`~burstloc.web.server.WebServer` (Starlette on uvicorn, the ``web`` extra) serves the
page and pushes the news by Server-Sent Events. The page is plain JavaScript drawing the
network (:mod:`burstloc.layout`) on a canvas; every asset is served from the package.

This layer imports the base and :mod:`burstloc.live` only: it reads the monitor's own records,
never the simulator.
"""

from __future__ import annotations

import os
from typing import Any

from burstloc.layout import read_layout
from burstloc.web.hub import Hub
from burstloc.web.server import WebServer, check_access, parse_bind
from burstloc.web.view import View

__all__ = ["Hub", "View", "WebServer", "check_access", "control_room", "parse_bind"]


def control_room(
    network: str | os.PathLike[str],
    meters: list[str] | tuple[str, ...],
    capture_interval: float,
    *,
    host: str = "127.0.0.1",
    port: int = 0,
    token: str | None = None,
    meta: dict[str, Any] | None = None,
    incidents: Any = None,
) -> WebServer:
    """A (not yet started) server of the page for a monitor of ``meters`` on ``network``; its
    :attr:`WebServer.hub` is the observer to give the live loop. With ``incidents`` (an
    :class:`~burstloc.incidents.store.IncidentStore`) the page lists the incidents and
    operators act on them (:mod:`burstloc.web.incidents`).

    Raises:
        ConfigError: a non-loopback ``host`` without a token.
        NetworkError: the network file cannot be read.
    """
    check_access(host, token)
    layout = read_layout(network)
    info = {"network": os.path.basename(os.fspath(network)), **(meta or {})}
    view = View(meters, capture_interval, info)
    return WebServer(
        Hub(), view, layout.to_json(), host=host, port=port, token=token, incidents=incidents
    )
