"""Capture what the simulation stack prints, warns and logs, instead of letting it reach the user.

TSNet prints progress to stdout and warns through :mod:`warnings`; WNTR warns and logs. While a
:func:`capture_diagnostics` block runs, all three are collected into a :class:`Diagnostics`
record (kept in a scenario's metadata) and nothing reaches the terminal.

Blocks nest: an inner block's records are passed on to the enclosing block when it ends.

Not thread-safe: it swaps process-wide state (``sys.stdout``, the warning filters); callers
serialise simulations (see :mod:`burstloc.sim.transient.tsnet`).
"""

from __future__ import annotations

import contextlib
import io
import logging
import re
import sys
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

#: TSNet's progress and timing lines: dropped, everything else it prints is kept.
_PROGRESS = re.compile(
    r"^(Transient simulation completed|Estimated simulation time|Simulation time step"
    r"|Total Time Step in this simulation)"
)
_NEGATIVE_PRESSURE = re.compile(r"Negative pressure on node (\S+?)\.?(?:\s|$)")
_ACTIVE: list[Diagnostics] = []


@dataclass
class Diagnostics:
    """What a block of simulation code printed, warned and logged.

    Attributes:
        warnings: distinct warnings as ``"Category: message"``, in order of first appearance
            (each distinct message once).
        messages: printed lines other than progress reports, and WARNING-or-worse log records
            of the ``wntr`` and ``tsnet`` loggers.
    """

    warnings: list[str] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)

    def negative_pressure_nodes(self) -> list[str]:
        """Nodes TSNet reported negative pressure at (names as TSNet's messages give them)."""
        nodes = {m.group(1) for w in self.warnings for m in _NEGATIVE_PRESSURE.finditer(w)}
        return sorted(nodes)


class _ListHandler(logging.Handler):
    def __init__(self, sink: list[str]) -> None:
        super().__init__(level=logging.WARNING)
        self._sink = sink

    def emit(self, record: logging.LogRecord) -> None:
        self._sink.append(f"{record.name} {record.levelname}: {record.getMessage()}")


@contextlib.contextmanager
def capture_diagnostics(loggers: tuple[str, ...] = ("wntr", "tsnet")) -> Iterator[Diagnostics]:
    """Collect stdout, warnings and the named loggers' records into a :class:`Diagnostics`."""
    diag = Diagnostics()
    _ACTIVE.append(diag)
    seen: set[str] = set()
    log_lines: list[str] = []

    def show(message, category, filename, lineno, file=None, line=None):  # type: ignore[no-untyped-def]
        text = f"{category.__name__}: {message}"
        if text not in seen:
            seen.add(text)
            diag.warnings.append(text)

    handler = _ListHandler(log_lines)
    targets = [logging.getLogger(name) for name in loggers]
    out = io.StringIO()
    with warnings.catch_warnings():
        # "default": each distinct message once per code location (cheap in TSNet's hot loop,
        # which warns on every time step); catch_warnings resets the once-registries.
        warnings.simplefilter("default")
        warnings.showwarning = show
        for logger in targets:
            logger.addHandler(handler)
        try:
            with contextlib.redirect_stdout(out):
                yield diag
        finally:
            for logger in targets:
                logger.removeHandler(handler)
            printed = [ln.strip() for ln in out.getvalue().splitlines()]
            diag.messages.extend(ln for ln in printed if ln and not _PROGRESS.match(ln))
            diag.messages.extend(log_lines)
            _ACTIVE.pop()
            pass_on(diag)


def pass_on(diag: Diagnostics) -> None:
    """Add ``diag``'s records to the innermost :func:`capture_diagnostics` block running (as a
    block nested in it passes its own on when it ends); nothing when none runs."""
    for recording, depth in _RECORDING:
        if len(_ACTIVE) == depth:  # a block directly in the recorded one
            recording.events.append(("passed", diag))
    if _ACTIVE:
        outer = _ACTIVE[-1]
        outer.warnings.extend(w for w in diag.warnings if w not in outer.warnings)
        outer.messages.extend(diag.messages)


_RECORDING: list[tuple[Recording, int]] = []


@dataclass
class Recording:
    """What a block printed, logged (the ``wntr`` and ``tsnet`` loggers), warned and passed on
    from the capture blocks in it, in order (:func:`recording`)."""

    events: list[tuple[str, Any]] = field(default_factory=list)

    def replay(self) -> None:
        """Print, log, warn and pass it on again, into the :func:`capture_diagnostics` block
        running (which then holds what it would hold had the recorded block run again here);
        nothing when none runs (it reached the terminal once)."""
        if not _ACTIVE:
            return
        for kind, item in self.events:
            if kind == "print":
                sys.stdout.write(item)
            elif kind == "log":
                logging.getLogger(item.name).handle(item)
            elif kind == "warning":
                warnings.showwarning(*item)
            else:
                pass_on(item)


class _RecordingHandler(logging.Handler):
    def __init__(self, recording: Recording) -> None:
        super().__init__(level=logging.NOTSET)
        self._recording = recording

    def emit(self, record: logging.LogRecord) -> None:
        self._recording.events.append(("log", record))


class _Tee(io.TextIOBase):
    """A text stream writing to ``target`` and recording what it wrote."""

    def __init__(self, target: Any, recording: Recording) -> None:
        self._target = target
        self._recording = recording

    def write(self, text: str) -> int:
        self._recording.events.append(("print", text))
        return int(self._target.write(text))

    def flush(self) -> None:
        self._target.flush()


@contextlib.contextmanager
def recording(loggers: tuple[str, ...] = ("wntr", "tsnet")) -> Iterator[Recording]:
    """Record what the block prints, logs, warns and what the capture blocks in it pass on,
    letting all of it through as without the recording: :meth:`Recording.replay` does it again
    (for a result made once and used again, as if it were made each time)."""
    record = Recording()
    _RECORDING.append((record, len(_ACTIVE)))
    handler = _RecordingHandler(record)
    targets = [logging.getLogger(name) for name in loggers]
    shown = warnings.showwarning

    def show(*args: Any, **kwargs: Any) -> None:
        record.events.append(("warning", args))
        shown(*args, **kwargs)

    warnings.showwarning = show
    for logger in targets:
        logger.addHandler(handler)
    try:
        with contextlib.redirect_stdout(_Tee(sys.stdout, record)):
            yield record
    finally:
        for logger in targets:
            logger.removeHandler(handler)
        warnings.showwarning = shown
        _RECORDING.pop()
