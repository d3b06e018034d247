"""The paper's real-time loop: readings -> complete steps -> windows -> detector -> rules.

:class:`BurstLocator` assembles windows of readings with
:class:`~burstloc.live.windows.ReadingStream`
(paper IV.B, "Fetching data"), runs a window detector (:mod:`burstloc.localize.detection`) and
the paper's rules (:func:`burstloc.localize.paper_rules.locate`) on each.
"""

from __future__ import annotations

from collections.abc import AsyncIterable, AsyncIterator, Iterable, Iterator, Sequence
from typing import Any

import networkx as nx

from burstloc.exceptions import StreamError
from burstloc.live.windows import ReadingStream
from burstloc.localize.paper_rules import Localization, WindowDetector, WindowOutcome, locate
from burstloc.readings import Item, Window

__all__ = ["BurstLocator"]


class BurstLocator:
    """The real-time loop: readings -> complete steps -> windows -> detector -> rules.

    ``meters`` must all be nodes of ``graph`` (a :class:`~burstloc.exceptions.StreamError`
    names the first one that is not). Stream options (``timeout``, ``missing``, ``period``,
    ``origin``) are passed to :class:`~burstloc.live.windows.ReadingStream`.
    """

    def __init__(
        self,
        graph: nx.DiGraph,
        meters: Sequence[str],
        detector: WindowDetector,
        interval: int,
        **stream_options: Any,
    ) -> None:
        for m in meters:
            if m not in graph:
                raise StreamError(f"meter {m!r} is not a junction of the network")
        self.graph = graph
        self.detector = detector
        self.stream = ReadingStream(meters, interval, **stream_options)
        self.meters: tuple[str, ...] = self.stream.meters

    def process(self, window: Window) -> WindowOutcome:
        """Run the detector and the rules on one window."""
        changes = self.detector.detect(window)
        loc = None
        if any(changes.values()):
            loc = locate(
                self.graph, changes, window.means(), window.decision_time, order=self.meters
            )
        return WindowOutcome(window, changes, loc)

    def push(self, item: Item) -> list[WindowOutcome]:
        """Feed one reading or step; return the outcomes of the windows it completed."""
        return [self.process(w) for w in self.stream.push(item)]

    def outcomes(self, source: Iterable[Item]) -> Iterator[WindowOutcome]:
        """Every window's outcome over a feed (flushed at its end)."""
        for w in self.stream.windows(source):
            yield self.process(w)

    def run(self, source: Iterable[Item]) -> Iterator[Localization]:
        """The localizations of a feed, one per window that decided."""
        for o in self.outcomes(source):
            if o.localization is not None:
                yield o.localization

    async def arun(
        self, source: AsyncIterable[Item] | Iterable[Item]
    ) -> AsyncIterator[Localization]:
        """Async twin of :meth:`run`."""
        async for w in self.stream.awindows(source):
            o = self.process(w)
            if o.localization is not None:
                yield o.localization

    def first(self, source: Iterable[Item]) -> WindowOutcome | None:
        """The first window that decided (the paper's single localization attempt), or ``None``."""
        for o in self.outcomes(source):
            if o.localization is not None:
                return o
        return None
