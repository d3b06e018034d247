"""The control-room page's server: an ASGI app (Starlette) run by uvicorn on its own thread.

Routes (GET; any other method is refused with 405: nothing here changes the monitor):
``/`` the page, ``/static/...`` its script and style (from the package: no CDN),
``/network.json`` the drawing (:mod:`burstloc.layout`), ``/state.json`` the current state and
``/events`` the Server-Sent Events stream (a ``snapshot`` first, then ``update`` batches). The
incidents (``/incidents.json``, and the operators' actions, POST ``/incidents/ID/ACTION``: the
only writes, each with a token, refused from another site) are :mod:`burstloc.web.incidents`.

**Access.** Bound to a loopback address by default. A token (``--web-token`` or
``BURSTLOC_WEB_TOKEN``) is required for any other address and, when given, checked on every
request, in constant time (:func:`hmac.compare_digest`): as ``?token=`` (the page's first
load; a cookie then carries it), the cookie or an ``Authorization: Bearer`` header. A missing or
wrong token gets 401 and nothing else.

**Pushing.** A task on the server's event loop drains the hub's inbox when woken (a decision,
transient or event record, a message) and at least every :data:`POLL` seconds (the readings),
applies it to the :class:`~burstloc.web.view.View` and puts the news on each browser's bounded
queue; a browser whose queue is full is dropped (its page reconnects and starts again from a
snapshot).

**For other systems** (:mod:`burstloc.web.exports`): ``/metrics`` in Prometheus' text format
and ``/region.geojson``, the current record for GIS, under the same access rules.
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import ipaddress
import json
import threading
from collections.abc import AsyncIterator
from importlib import resources
from typing import Any

from burstloc.exceptions import ConfigError
from burstloc.web.exports import routes as export_routes
from burstloc.web.hub import Hub
from burstloc.web.incidents import routes as incident_routes
from burstloc.web.view import View

__all__ = ["POLL", "WebServer", "check_access", "parse_bind"]

#: Seconds between drains of the hub when nothing urgent woke the server.
POLL = 0.2
#: News batches a browser may have waiting before it is dropped.
CLIENT_QUEUE = 512
_COOKIE = "burstloc_token"


def parse_bind(text: str) -> tuple[str, int]:
    """``[HOST:]PORT`` → (host, port); the host defaults to 127.0.0.1.

    Raises:
        ConfigError: not ``[HOST:]PORT`` with a port in 0..65535.
    """
    host, sep, port = text.rpartition(":")
    host = host.strip("[]") if sep else "127.0.0.1"
    try:
        number = int(port)
    except ValueError:
        raise ConfigError(f"--web wants [HOST:]PORT, got {text!r}") from None
    if not (0 <= number <= 65535) or not host:
        raise ConfigError(f"--web wants [HOST:]PORT with a port in 0..65535, got {text!r}")
    return host, number


def _loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_access(host: str, token: str | None) -> None:
    """Refuse to serve a non-loopback address without a token.

    Raises:
        ConfigError: ``host`` is not a loopback address and ``token`` is empty.
    """
    if not token and not _loopback(host):
        raise ConfigError(
            f"--web on {host} (not a loopback address) needs a token: --web-token or the "
            "environment variable BURSTLOC_WEB_TOKEN"
        )


def _asset(name: str) -> bytes:
    return (resources.files("burstloc.web") / "static" / name).read_bytes()


_TYPES = {
    "map.js": "text/javascript; charset=utf-8",
    "chart.js": "text/javascript; charset=utf-8",
    "app.js": "text/javascript; charset=utf-8",
    "incidents.js": "text/javascript; charset=utf-8",
    "style.css": "text/css; charset=utf-8",
    "index.html": "text/html; charset=utf-8",
}


class WebServer:
    """The page's server for one monitor: ``start()`` serves on a thread, ``stop()`` ends it."""

    def __init__(
        self,
        hub: Hub,
        view: View,
        network: dict[str, Any],
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        token: str | None = None,
        incidents: Any = None,
    ) -> None:
        check_access(host, token)
        self.hub, self.view = hub, view
        #: The incident store the page lists and acts on (``None``: incidents are not kept).
        self.incidents = incidents
        self.host, self.port, self.token = host, port, token or None
        self._network = json.dumps(network, separators=(",", ":")).encode()
        #: ``/metrics``' :class:`~burstloc.web.metrics.MonitorMetrics` and ``/region.geojson``'s
        #: :class:`~burstloc.web.exports.RegionExport` (``None``: not served).
        self.metrics: Any = None
        self.region: Any = None
        self._clients: set[asyncio.Queue[bytes | None]] = set()
        self._wake: asyncio.Event | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._server: Any = None
        self._thread: threading.Thread | None = None
        self._started = threading.Event()
        self.app = self._make_app()

    # ------------------------------------------------------------------ the app
    def _authorized(self, request: Any) -> bool:
        if self.token is None:
            return True
        given = request.query_params.get("token") or request.cookies.get(_COOKIE) or ""
        auth = request.headers.get("authorization", "")
        if not given and auth.lower().startswith("bearer "):
            given = auth[7:]
        return hmac.compare_digest(given.encode(), self.token.encode())

    def _make_app(self) -> Any:
        from starlette.applications import Starlette
        from starlette.responses import JSONResponse, PlainTextResponse, Response
        from starlette.routing import Route

        server = self

        async def page(request: Any) -> Any:
            response = Response(_asset("index.html"), media_type=_TYPES["index.html"])
            if server.token is not None and request.query_params.get("token"):
                response.set_cookie(_COOKIE, server.token, httponly=True, samesite="strict")
            return response

        async def static(request: Any) -> Any:
            name = request.path_params["name"]
            if name not in _TYPES or name == "index.html":
                return PlainTextResponse("not found", status_code=404)
            return Response(_asset(name), media_type=_TYPES[name])

        async def network(request: Any) -> Any:
            return Response(server._network, media_type="application/json")

        async def state(request: Any) -> Any:
            return JSONResponse(server.view.snapshot())

        async def events(request: Any) -> Any:
            from starlette.responses import StreamingResponse

            return StreamingResponse(
                server._stream(request),
                media_type="text/event-stream",
                headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
            )

        class Guard:
            """401 without the token, 405 for anything but GET/HEAD (POST to the incidents'
            actions excepted): before any route."""

            def __init__(self, app: Any) -> None:
                self.app = app

            async def __call__(self, scope: Any, receive: Any, send: Any) -> None:
                if scope["type"] == "http":
                    from starlette.requests import Request

                    request = Request(scope)
                    if not server._authorized(request):
                        reply: Any = PlainTextResponse("unauthorized", status_code=401)
                        return await reply(scope, receive, send)
                    write = request.method == "POST" and request.url.path.startswith("/incidents/")
                    if request.method not in ("GET", "HEAD") and not write:
                        reply = PlainTextResponse("read-only", status_code=405)
                        return await reply(scope, receive, send)
                await self.app(scope, receive, send)

        @contextlib.asynccontextmanager
        async def lifespan(app: Any) -> AsyncIterator[None]:
            task = asyncio.create_task(server._pump())
            try:
                yield
            finally:
                task.cancel()

        routes = [
            *export_routes(server),
            Route("/", page),
            Route("/static/{name}", static),
            Route("/network.json", network),
            Route("/state.json", state),
            Route("/events", events),
            *incident_routes(server),
        ]
        app = Starlette(routes=routes, lifespan=lifespan)
        return Guard(app)

    # ------------------------------------------------------------------ pushing
    async def _pump(self) -> None:
        self._loop = loop = asyncio.get_running_loop()
        self._wake = wake = asyncio.Event()

        def wake_up() -> None:
            loop.call_soon_threadsafe(wake.set)

        self.hub.wake = wake_up
        self._started.set()
        try:
            while True:
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(wake.wait(), POLL)
                wake.clear()
                items = self.hub.drain()
                if not items:
                    continue
                news = self.view.take(items)
                if news and self._clients:
                    self._broadcast(_event("update", news))
        finally:
            self.hub.wake = None

    def _close_clients(self) -> None:
        """End every page's stream (the server is stopping)."""
        for queue in list(self._clients):
            while not queue.empty():
                queue.get_nowait()
            queue.put_nowait(None)
        self._clients.clear()

    def _broadcast(self, data: bytes) -> None:
        for queue in list(self._clients):
            try:
                queue.put_nowait(data)
            except asyncio.QueueFull:  # too slow: dropped; its page reconnects
                self._clients.discard(queue)
                with contextlib.suppress(asyncio.QueueFull):
                    queue.get_nowait()
                    queue.put_nowait(None)

    async def _stream(self, request: Any) -> AsyncIterator[bytes]:
        queue: asyncio.Queue[bytes | None] = asyncio.Queue(CLIENT_QUEUE)
        # the snapshot and the queue from the same instant (no await between): nothing missed,
        # nothing twice
        self._clients.add(queue)
        try:
            yield b"retry: 1000\n\n" + _event("snapshot", self.view.snapshot())
            while True:
                try:
                    data = await asyncio.wait_for(queue.get(), 15.0)
                except asyncio.TimeoutError:
                    yield b": keep-alive\n\n"
                    continue
                if data is None:
                    return
                yield data
        finally:
            self._clients.discard(queue)

    # ------------------------------------------------------------------ running
    @property
    def url(self) -> str:
        """The page's address (with the token, when one is needed)."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        query = "" if self.token is None else f"?token={self.token}"
        return f"http://{host}:{self.port}/{query}"

    def start(self) -> None:
        """Serve on a daemon thread; return once the server listens (the port is then known).

        Raises:
            ConfigError: the address cannot be bound.
        """
        import socket

        import uvicorn

        family = socket.AF_INET6 if ":" in self.host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((self.host, self.port))
        except OSError as exc:
            sock.close()
            raise ConfigError(f"--web cannot listen on {self.host}:{self.port}: {exc}") from exc
        sock.listen(128)  # from now on a browser is queued, not refused, until uvicorn accepts
        self.port = sock.getsockname()[1]
        config = uvicorn.Config(
            self.app,
            log_level="warning",
            access_log=False,
            lifespan="on",
            timeout_graceful_shutdown=1,
        )
        self._server = uvicorn.Server(config)
        self._thread = threading.Thread(
            target=self._server.run, kwargs={"sockets": [sock]}, name="burstloc-web", daemon=True
        )
        self._thread.start()
        server = self._server
        if not (self._started.wait(30) and _until(lambda: server.started, 30)):
            raise ConfigError("the web server did not start within 30 s")

    def stop(self) -> None:
        """Stop serving (open pages are disconnected) and wait for the thread."""
        if self._server is not None and self._thread is not None:
            if self._loop is not None:
                with contextlib.suppress(RuntimeError):  # its loop has already closed
                    self._loop.call_soon_threadsafe(self._close_clients)
            self._server.should_exit = True
            self._thread.join(10)


def _until(condition: Any, seconds: float) -> bool:
    """Whether ``condition()`` comes true within ``seconds`` (checked every 10 ms)."""
    import time

    end = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > end:
            return False
        time.sleep(0.01)
    return True


def _event(name: str, doc: Any) -> bytes:
    return f"event: {name}\ndata: {json.dumps(doc, separators=(',', ':'))}\n\n".encode()
