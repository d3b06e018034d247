"""An incident's picture for a work order: the page's ``?snapshot=ID`` view rendered to PNG.

The snapshot view (``static/app.js``) draws one incident from the store: the map around the
record's search region with the named pipe above it and the pipes' names, and the incident
panel (where, how sure, its state and history). It opens no event stream and polls nothing, so
the page finishes loading; it marks itself ready (``<body data-ready="1">``) once drawn.

:func:`incident_png` serves that view on a loopback port (a :class:`~burstloc.web.server.
WebServer` over the store) and has headless Chromium (Debian's ``chromium``) take the picture:
``--screenshot`` with a virtual-time budget, during which Chromium runs the page's script and
waits for each of its requests; no wall-clock sleep. Chromium prints the page (``--dump-dom``)
in the same run, and the picture is refused unless the page says it was ready: a picture of a
page still loading is never written.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

from burstloc.exceptions import ConfigError, OutputError

__all__ = ["BUDGET_MS", "CHROMIUM", "DEFAULT_SIZE", "find_chromium", "incident_png", "parse_size"]

#: The browsers tried, in order (the first on PATH is used), unless ``BURSTLOC_CHROMIUM`` names
#: one.
CHROMIUM = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
#: The picture's size in pixels when none is asked for (the page's own layout at a desk).
DEFAULT_SIZE = (1400, 900)
#: Virtual milliseconds the page may run before the picture (its requests do not count: virtual
#: time stands still while one is pending). The snapshot view needs none beyond its requests.
BUDGET_MS = 5000
#: Seconds of real time Chromium may take in all (a loaded machine is slow; a hung one is not).
TIMEOUT = 180.0
_SMALLEST, _LARGEST = 320, 8000


def parse_size(text: str) -> tuple[int, int]:
    """``WIDTHxHEIGHT`` in pixels → (width, height).

    Raises:
        ConfigError: not two whole numbers in 320..8000 joined by ``x``.
    """
    width, sep, height = text.lower().partition("x")
    try:
        size = (int(width), int(height))
    except ValueError:
        size = (0, 0)
    if not sep or not all(_SMALLEST <= v <= _LARGEST for v in size):
        raise ConfigError(
            f"--size wants WIDTHxHEIGHT in pixels, each {_SMALLEST}..{_LARGEST}, got {text!r}"
        )
    return size


def find_chromium() -> str:
    """The headless browser to use: ``BURSTLOC_CHROMIUM``, else the first of :data:`CHROMIUM`
    on PATH.

    Raises:
        ConfigError: none is installed.
    """
    named = os.environ.get("BURSTLOC_CHROMIUM")
    if named:
        found = shutil.which(named)
        if found is None:
            raise ConfigError(f"BURSTLOC_CHROMIUM={named!r} is not an executable")
        return found
    for name in CHROMIUM:
        found = shutil.which(name)
        if found is not None:
            return found
    raise ConfigError(
        "an incident's picture needs Chromium (headless): apt-get install chromium, or name "
        "the browser in the environment variable BURSTLOC_CHROMIUM"
    )


def incident_png(
    store: Any,
    incident: int,
    network: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    size: tuple[int, int] = DEFAULT_SIZE,
) -> Path:
    """Write the picture of ``incident`` (in ``store``, an :class:`~burstloc.incidents.store.
    IncidentStore`) on ``network`` to ``out`` (PNG, ``size`` pixels); return ``out``.

    Raises:
        UnknownIncidentError: no such incident.
        ConfigError: the incident has no located record (nothing to draw), its record names a
            pipe or meter the network lacks (another network's record), or no Chromium.
        NetworkError: the network file cannot be read.
        OutputError: Chromium did not draw the page, or drew it before it was ready (its
            message is given).
    """
    from burstloc.gis import record_geojson
    from burstloc.layout import read_layout
    from burstloc.web import control_room

    doc = store.get(incident)
    record = doc.get("record")
    if not isinstance(record, dict) or not (record.get("region") or record.get("position")):
        raise ConfigError(
            f"incident {incident} ({doc['kind']}: {doc['summary']}) has no located record: "
            "nothing to draw"
        )
    # the record on this network's drawing, checked as the GeoJSON export checks it
    record_geojson(read_layout(network), record, source=f"incident {incident}'s record")
    browser = find_chromium()
    # the capture interval is not shown: the picture has no chart
    server = control_room(network, list(record.get("meters") or []), 1.0, incidents=store)
    server.start()
    try:
        url = f"{server.url}?snapshot={incident}"
        _screenshot(browser, url, Path(out), size)
    finally:
        server.stop()
    return Path(out)


def _screenshot(browser: str, url: str, out: Path, size: tuple[int, int]) -> None:
    with tempfile.TemporaryDirectory(prefix="burstloc-png-") as profile:
        shot = Path(profile) / "page.png"
        command = [
            browser,
            "--headless",
            "--disable-gpu",
            "--disable-dev-shm-usage",
            "--disable-crash-reporter",
            "--no-first-run",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            f"--user-data-dir={profile}",
            f"--window-size={size[0]},{size[1]}",
            f"--virtual-time-budget={BUDGET_MS}",
            f"--screenshot={shot}",
            "--dump-dom",
            url,
        ]
        if hasattr(os, "geteuid") and os.geteuid() == 0:
            command.insert(1, "--no-sandbox")  # Chromium's sandbox refuses to run as root
        try:
            done = subprocess.run(
                command, capture_output=True, text=True, timeout=TIMEOUT, check=False
            )
        except subprocess.TimeoutExpired:
            raise OutputError(
                f"cannot write {out}: Chromium did not draw the page within {TIMEOUT:g} s"
            ) from None
        if done.returncode != 0 or not shot.exists():
            said = (done.stderr.strip().splitlines() or ["(nothing)"])[-1]
            raise OutputError(
                f"cannot write {out}: Chromium did not draw the page (exit {done.returncode}): "
                f"{said}"
            )
        if 'data-ready="1"' not in done.stdout:
            raise OutputError(
                f"cannot write {out}: the page was not ready when Chromium took the picture"
            )
        from burstloc._atomic import write_bytes

        write_bytes(out, shot.read_bytes())
