"""A webhook receiver that fails on purpose: a real HTTP server (``http.server``) on a loopback
port, in a thread. ``fault()`` decides each request's fate: ``None`` (accepted: 200, the alert
recorded), an HTTP status (answered with it), ``"close"`` (the connection closed without an
answer) or ``"hang"`` (no answer until the receiver stops: the sender's timeout). Only accepted
alerts are in :attr:`Receiver.accepted`, in the order they were accepted."""

from __future__ import annotations

import json
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

Fault = Callable[[], "int | str | None"]


class Receiver:
    """The server's record: what was accepted, how many requests came."""

    def __init__(self, server: ThreadingHTTPServer, fault: Fault) -> None:
        self.server = server
        self.fault = fault
        self.url = f"http://127.0.0.1:{server.server_port}/hook"
        #: Accepted alerts: (Idempotency-Key, body), in order.
        self.accepted: list[tuple[str, dict[str, Any]]] = []
        self.requests = 0
        self.refused: list[int | str] = []
        self.release = threading.Event()
        self.lock = threading.Lock()

    @property
    def events(self) -> list[tuple[int, str]]:
        """The accepted alerts as (incident, event)."""
        return [(body["incident"]["id"], body["event"]) for _, body in self.accepted]


def _handler(receiver: Receiver) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        def do_POST(self) -> None:
            body = self.rfile.read(int(self.headers["Content-Length"]))
            with receiver.lock:
                receiver.requests += 1
                fate = receiver.fault()
                if fate is None:
                    receiver.accepted.append((self.headers["Idempotency-Key"], json.loads(body)))
                else:
                    receiver.refused.append(fate)
            if fate == "hang":
                receiver.release.wait()
                self.close_connection = True
                return
            if fate == "close":
                self.close_connection = True
                return
            self.send_response(200 if fate is None else int(fate))
            self.send_header("Content-Length", "0")
            self.end_headers()

        def log_message(self, *args: Any) -> None:
            pass

    return Handler


@contextmanager
def receiver(fault: Fault = lambda: None) -> Iterator[Receiver]:
    """A running receiver; stopped (hung requests released) after."""
    server = ThreadingHTTPServer(("127.0.0.1", 0), BaseHTTPRequestHandler)
    server.daemon_threads = True
    got = Receiver(server, fault)
    server.RequestHandlerClass = _handler(got)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield got
    finally:
        got.release.set()
        server.shutdown()
        server.server_close()
