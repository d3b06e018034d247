"""``burstloc monitor --web``: the control-room page beside the live loop; ``--replay-speed``."""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections.abc import Callable
from typing import Any

from burstloc.exceptions import ConfigError

__all__ = ["add_arguments", "linger", "start"]

TOKEN_VARIABLE = "BURSTLOC_WEB_TOKEN"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The ``web`` option group of ``burstloc monitor``."""
    web = parser.add_argument_group("control-room page")
    web.add_argument(
        "--web",
        metavar="[HOST:]PORT",
        help="serve a live read-only page of the network, meters and decisions (host "
        "127.0.0.1 unless given; any other address needs a token); needs burstloc[web]",
    )
    web.add_argument(
        "--web-token",
        metavar="TOKEN",
        help=f"token the page asks for (default: the environment variable {TOKEN_VARIABLE})",
    )
    web.add_argument(
        "--replay-speed",
        type=float,
        metavar="X",
        help="play the readings file at X times real time (by its timestamps), e.g. for a demo",
    )


def start(args: argparse.Namespace, monitor: Any, incidents: Any = None) -> Any:
    """The started page server for ``monitor`` (``None`` without ``--web``); its address is
    told on stderr. With ``incidents`` (the monitor's incident store) the page lists them and
    operators act on them.

    Raises:
        ConfigError: a bad ``--web``, a non-loopback address without a token, the web extra
            missing, the port taken.
    """
    if args.replay_speed is not None and args.mqtt is not None:
        raise ConfigError("--replay-speed plays a readings file; it cannot pace an MQTT feed")
    if args.web is None:
        if args.web_token is not None:
            raise ConfigError("--web-token needs --web")
        return None
    try:
        import starlette  # noqa: F401
        import uvicorn  # noqa: F401
    except ImportError:
        raise ConfigError(
            "--web needs the web extra: pip install 'burstloc[web]' (Starlette and uvicorn)"
        ) from None
    from burstloc.web import control_room, parse_bind

    host, port = parse_bind(args.web)
    token = args.web_token if args.web_token is not None else os.environ.get(TOKEN_VARIABLE)
    server = control_room(
        args.network,
        monitor.meters,
        monitor.calibration.capture_interval,
        host=host,
        port=port,
        token=token or None,
        meta={"detector": monitor.detector, "localizer": monitor.localizer},
        incidents=incidents,
    )
    server.start()
    shown = server.url if server.token is None else server.url.split("?")[0] + "?token=…"
    print(f"burstloc monitor: control room at {shown}", file=sys.stderr, flush=True)
    return server


def linger(server: Any, stopped: Callable[[], bool]) -> None:
    """After a file's last reading: keep the page up until SIGTERM or Ctrl-C."""
    print(
        "burstloc monitor: the feed has ended; the page stays up until interrupted (Ctrl-C)",
        file=sys.stderr,
        flush=True,
    )
    try:
        while not stopped():
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
