"""``burstloc monitor`` as a service: its settings file (re-read on SIGHUP), the page's metrics
and GeoJSON export.

* ``--settings FILE.toml``: every option in one file (:mod:`burstloc.cli._settings`); options on
  the command line override it.
* **SIGHUP** re-reads the file while the monitor reads its feed and applies what can change
  without a restart (:data:`RELOADABLE`): ``health-every``, ``save-every``, ``silent-after``,
  ``web-token`` and ``crs``. The change is applied between two input items (never inside a
  step) and said in one line; a key that changed but needs a restart is named as such, and a
  key the command line gave keeps the command line's value. A file that no longer reads (bad
  TOML, a bad value) changes nothing: the error is said and the monitor runs on as it was.
* With ``--web``, the page's server also serves ``/metrics`` (:mod:`burstloc.web.metrics`: the
  loop's counters, the decision latency timed by a :class:`~burstloc.live.timing.RecordTimer`
  put in front of the loop's observer) and ``/region.geojson`` (the current record, in WGS 84
  with ``--crs``).
"""

from __future__ import annotations

import argparse
import math
import os
import signal
from collections.abc import Callable, Iterator
from typing import Any

from burstloc.exceptions import ConfigError

__all__ = ["RELOADABLE", "add_arguments", "attach", "reloading"]

#: The settings SIGHUP applies to a running monitor: where each goes, what it must be.
RELOADABLE = ("health-every", "save-every", "silent-after", "web-token", "crs")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The ``service`` option group of ``burstloc monitor``."""
    group = parser.add_argument_group("service")
    group.add_argument(
        "--settings",
        metavar="FILE.toml",
        help="every option of this command in a TOML file, 'key = value' with the options' "
        "names without their dashes (network = ..., capture-interval = 0.2); options on the "
        "command line override it; SIGHUP re-reads " + ", ".join(RELOADABLE),
    )
    group.add_argument(
        "--crs",
        metavar="EPSG:NNNN",
        help="the network's coordinate reference system: the page's GeoJSON download "
        "(/region.geojson) in WGS 84 longitude, latitude; needs pyproj",
    )


def attach(args: argparse.Namespace, web: Any, loop: Any, link: Any) -> Any:
    """Serve ``/metrics`` and ``/region.geojson`` from ``web`` (the page's server, ``None``
    without ``--web``) for ``loop``; ``link``: the MQTT link, if any. Returns the
    :class:`~burstloc.web.metrics.MonitorMetrics` (``None`` without ``--web``); a
    :class:`~burstloc.live.timing.RecordTimer` is put in front of the loop's observer.

    Raises:
        ConfigError: ``--crs`` without ``--web``, or a ``--crs`` pyproj does not know.
    """
    if web is None:
        if args.crs is not None:
            raise ConfigError("--crs is for the page's GeoJSON download: it needs --web")
        return None
    from burstloc import __version__
    from burstloc.layout import read_layout
    from burstloc.live.timing import RecordTimer
    from burstloc.web.exports import RegionExport
    from burstloc.web.metrics import MonitorMetrics

    web.region = RegionExport(read_layout(args.network), args.crs)
    timer = RecordTimer(loop.observer)
    loop.observer = loop.monitor.observer = timer
    monitor = loop.monitor
    info = {
        "version": __version__,
        "network": os.path.basename(args.network),
        "detector": monitor.detector,
        "localizer": monitor.localizer,
    }
    web.metrics = MonitorMetrics(loop, timer, link=link, inbox=web.hub.inbox, info=info)
    return web.metrics


def reloading(
    items: Iterator[Any],
    args: argparse.Namespace,
    *,
    loop: Any,
    web: Any,
    metrics: Any,
    report: Callable[[str, str], None],
) -> Iterator[Any]:
    """``items``, with SIGHUP re-reading the settings file between two of them (module
    docstring); ``items`` as they are without ``--settings`` (SIGHUP then ends the process,
    as it always did)."""
    source = getattr(args, "settings_source", None)
    if source is None or not hasattr(signal, "SIGHUP"):
        return items
    return _reloading(items, _Reloader(args, source, loop, web, metrics, report))


def _reloading(items: Iterator[Any], reloader: _Reloader) -> Iterator[Any]:
    hup = {"pending": False}

    def on_hup(signum: int, frame: Any) -> None:
        hup["pending"] = True

    previous = signal.signal(signal.SIGHUP, on_hup)
    try:
        for item in items:
            if hup["pending"]:
                hup["pending"] = False
                reloader.reload()
            yield item
    finally:
        signal.signal(signal.SIGHUP, previous)


class _Reloader:
    """Applies the re-read settings to the running monitor."""

    def __init__(
        self,
        args: argparse.Namespace,
        source: Any,
        loop: Any,
        web: Any,
        metrics: Any,
        report: Callable[[str, str], None],
    ) -> None:
        self.args, self.source, self.loop, self.web = args, source, loop, web
        self.metrics, self.report = metrics, report

    def _count(self, outcome: str) -> None:
        if self.metrics is not None:
            self.metrics.reloads[outcome] += 1

    def reload(self) -> None:
        """Re-read the file; apply what may change; say what was done."""
        where = f"settings file {self.source.path}"
        try:
            values = self.source.read()
            changed = {d: v for d, v in values.items() if v != getattr(self.args, d)}
            now = {d: v for d, v in changed.items() if self._reloadable(d)}
            for dest, value in now.items():
                self._check(self.source.spec.key(dest), value)
        except ConfigError as exc:
            self._count("refused")
            self.report("settings", f"SIGHUP: {exc}; nothing changed")
            return
        said = [
            _change(self.source.spec.key(d), getattr(self.args, d), v, d) for d, v in now.items()
        ]
        for dest, value in now.items():
            self._apply(dest, value)
            setattr(self.args, dest, value)
        self._count("applied")
        later = sorted(self.source.spec.key(d) for d in changed if d not in now)
        text = f"SIGHUP: re-read {where}: " + ("; ".join(said) if said else "nothing to change")
        if later:
            text += f"; changed but needs a restart: {', '.join(later)}"
        if self.source.command_line:
            kept = sorted(self.source.spec.key(d) for d in self.source.command_line)
            text += f"; kept from the command line: {', '.join(kept)}"
        self.report("settings", text)

    def _reloadable(self, dest: str) -> bool:
        """Whether SIGHUP changes ``dest`` (the page's keys only with the page)."""
        key = self.source.spec.key(dest)
        return key in RELOADABLE and (self.web is not None or key not in ("web-token", "crs"))

    def _check(self, key: str, value: Any) -> None:
        """Refuse a value the running monitor cannot take (``ConfigError`` naming the key)."""
        if key in ("health-every", "save-every") and not 0 <= value < math.inf:
            raise ConfigError(f"{self.source.path}: key {key!r} must be >= 0, got {value}")
        if key == "silent-after" and not 0 < value < math.inf:
            raise ConfigError(f"{self.source.path}: key {key!r} must be > 0, got {value}")
        if key == "web-token" and self.web is not None:
            from burstloc.web import check_access

            check_access(self.web.host, _token(value))
        if key == "crs":
            from burstloc.web.exports import RegionExport

            RegionExport.check_crs(value)

    def _apply(self, dest: str, value: Any) -> None:
        key = self.source.spec.key(dest)
        if key == "health-every":
            self.loop.health_every = value
        elif key == "save-every":
            self.loop.save_every = value
        elif key == "silent-after":
            self.loop.health.silent_after = float(value)
        elif key == "web-token":
            self.web.token = _token(value)
        elif key == "crs":
            self.web.region.crs = value


def _token(value: str | None) -> str | None:
    """The page's token from the settings (else the environment variable, as at start)."""
    from burstloc.cli._web import TOKEN_VARIABLE

    return (value if value is not None else os.environ.get(TOKEN_VARIABLE)) or None


def _change(key: str, before: Any, after: Any, dest: str) -> str:
    if dest == "web_token":
        return "web-token changed"
    return f"{key} {before} -> {after}"
