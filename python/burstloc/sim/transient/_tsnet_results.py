"""TSNet's ``Initializer`` reading EPANET's steady state by name instead of through pandas.

``tsnet.simulation.initialize.Initializer`` runs EPANET (WNTR's ``EpanetSimulator``) and then
reads its results one value at a time, ``results.node['head'].loc[t0, name]``, three times for
every reach of every pipe (``H = [head(start) + i * (head(end) - head(start)) / N ...]``): on
L-TOWN about 17 000 pandas look-ups, 0.1-0.2 s of each burst. While :func:`results_by_name`
runs, the ``Initializer`` gets the same results as a mapping per time from name to value: the
very float64 numbers pandas returns, so every head, flow and coefficient TSNet computes from
them is bit for bit the same (``tests/sim/test_intact.py`` and the reference heads of
``tests/sim/test_tsnet_compat.py`` check it). TSNet's own code runs unchanged; only the name
``wntr`` in its module points, meanwhile, to a stand-in whose ``sim.EpanetSimulator`` wraps
WNTR's.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

__all__ = ["results_by_name"]


class _ByName:
    """A WNTR result frame read as TSNet reads it, ``frame.loc[time, name]``, from one
    dictionary per time (made at its first read)."""

    def __init__(self, frame: Any) -> None:
        self._frame = frame
        self._times: dict[Any, dict[str, Any]] = {}

    @property
    def loc(self) -> _ByName:
        return self

    def __getitem__(self, key: tuple[Any, str]) -> Any:
        time, name = key
        row = self._times.get(time)
        if row is None:
            values = self._frame.loc[time]
            row = self._times[time] = dict(zip(values.index, values.to_numpy(), strict=True))
        return row[name]  # a KeyError for an unknown name, as pandas raises


class _Results:
    def __init__(self, results: Any) -> None:
        self.node = {key: _ByName(frame) for key, frame in results.node.items()}
        self.link = {key: _ByName(frame) for key, frame in results.link.items()}


class _Simulator:
    """WNTR's ``EpanetSimulator`` whose results are read by name."""

    def __init__(self, wntr: Any, model: Any) -> None:
        self._simulator = wntr.sim.EpanetSimulator(model)

    def run_sim(self, *args: Any, **kwargs: Any) -> _Results:
        return _Results(self._simulator.run_sim(*args, **kwargs))


@contextlib.contextmanager
def results_by_name() -> Iterator[None]:
    """Within the block, TSNet's ``Initializer`` reads EPANET's results by name (module
    docstring). Call with TSNet loaded (:func:`burstloc.sim.transient._tsnet_compat.load`)."""
    from tsnet.simulation import initialize

    wntr = initialize.wntr
    initialize.wntr = SimpleNamespace(
        sim=SimpleNamespace(EpanetSimulator=lambda model: _Simulator(wntr, model))
    )
    try:
        yield
    finally:
        initialize.wntr = wntr
