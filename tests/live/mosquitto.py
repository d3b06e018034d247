"""A real Mosquitto broker for the tests: its own config on a free loopback port, stopped after."""

from __future__ import annotations

import shutil
import socket
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

MOSQUITTO = shutil.which("mosquitto") or (
    "/usr/sbin/mosquitto" if Path("/usr/sbin/mosquitto").exists() else None
)


#: The topic on which the broker publishes its log of subscriptions: ``"<time>: <client> <qos>
#: <topic filter>"``.
SUBSCRIPTIONS = "$SYS/broker/log/M/subscribe"


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@contextmanager
def broker(folder: Path) -> Iterator[int]:
    """Run ``mosquitto`` on 127.0.0.1 (its config in ``folder``); yield its port."""
    if MOSQUITTO is None:
        raise RuntimeError("mosquitto is not installed: run `make setup` (see the README)")
    port = _free_port()
    conf = folder / "mosquitto.conf"
    conf.write_text(
        f"listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\n"
        # The log goes to the broker's own topics (a log file in ``folder`` is not writable once
        # a broker started as root drops to its own user, and then it logs nothing at all).
        # Each subscription is published on SUBSCRIPTIONS, so that a test can wait until a
        # client has subscribed instead of guessing how long that takes.
        "log_dest topic\nlog_type subscribe\nlog_type error\nlog_type warning\n"
        # Nagle's algorithm off on the broker's sockets too, as the monitor's documentation
        # advises: small records are not held back for a delayed acknowledgement.
        "set_tcp_nodelay true\n"
    )
    proc = subprocess.Popen([MOSQUITTO, "-c", str(conf)], stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120  # a guard against a hang, not a timing assumption
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
                break
            except OSError:
                if proc.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError(f"mosquitto did not start on port {port}") from None
                time.sleep(0.05)
        yield port
    finally:
        proc.terminate()
        proc.wait(timeout=10)
