"""Rate-limited messages for the operator: the live loop's bad data, silences and clock
corrections, told without flooding the terminal (:class:`Reporter`)."""

from __future__ import annotations

import time
from collections.abc import Callable

__all__ = ["Reporter"]


class Reporter:
    """Rate-limited messages: per kind, at most ``burst`` messages per ``every`` seconds; the
    number held back is told with the next message of that kind and by :meth:`close`."""

    def __init__(
        self, write: Callable[[str], None], *, burst: int = 5, every: float = 10.0
    ) -> None:
        self.write = write
        self.burst = burst
        self.every = every
        self._window: dict[str, tuple[float, int]] = {}
        self._held: dict[str, int] = {}
        self.counts: dict[str, int] = {}

    def __call__(self, kind: str, message: str) -> None:
        """Report ``message`` of ``kind`` unless too many of that kind came lately."""
        self.counts[kind] = self.counts.get(kind, 0) + 1
        now = time.monotonic()
        start, sent = self._window.get(kind, (now, 0))
        if now - start >= self.every:
            start, sent = now, 0
        if sent >= self.burst:
            self._held[kind] = self._held.get(kind, 0) + 1
            self._window[kind] = (start, sent)
            return
        held = self._held.pop(kind, 0)
        suffix = f" ({held} more {kind} messages not shown)" if held else ""
        self.write(f"burstloc monitor: {message}{suffix}")
        self._window[kind] = (start, sent + 1)

    def close(self) -> None:
        """Tell how many messages of each kind were held back and not yet told."""
        for kind, held in sorted(self._held.items()):
            self.write(f"burstloc monitor: {held} more {kind} messages not shown")
        self._held.clear()
