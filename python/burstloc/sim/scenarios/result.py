"""A simulated burst's result: the pressure head of every original junction (the meters; the
burst junction is left out), or of those its scenario's ``recorded`` names, on the simulator's
time grid, with the scenario's metadata (:class:`ScenarioResult`); it saves to and loads from
NPZ files, resamples onto a meter's clock, and names the file the CLI writes it to
(:func:`output_path`). :mod:`burstloc.sim.scenarios.scenario` says what is simulated,
:mod:`burstloc.sim.transient.tsnet` simulates it.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc._atomic import write_npz
from burstloc.sim.scenarios import capture

__all__ = ["ScenarioResult", "output_path"]


@dataclass(frozen=True, eq=False)
class ScenarioResult:
    """A simulated burst: pressure heads of the meters over time, and what produced them.

    Attributes:
        time: times, s, shape ``(T,)`` (TSNet's grid, or capture ticks after :meth:`resample`).
        heads: pressure head (hydraulic head minus elevation), m, shape ``(T, M)``.
        junctions: the ``M`` meter junctions (the network's original junctions, INP order).
        time_step: TSNet's time step, s.
        metadata: the scenario's parameters, ``pipe``, ``true_start``/``true_end`` (the pipe's
            ends in steady-state flow direction), ``burst_node``, ``time_step``, captured
            ``warnings``/``tsnet_messages``/``negative_pressure_nodes``, ``versions``,
            ``capture_interval``/``capture_phase`` (``None`` on the simulation grid), ...
    """

    time: NDArray[np.float64]
    heads: NDArray[np.float64]
    junctions: list[str]
    time_step: float
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def pipe(self) -> str:
        """The burst pipe."""
        return str(self.metadata["pipe"])

    @property
    def true_endpoints(self) -> tuple[str, str]:
        """The burst pipe's ``(start, end)`` in steady-state flow direction."""
        return str(self.metadata["true_start"]), str(self.metadata["true_end"])

    def node_label(self, node: str) -> str:
        """What a user calls ``node``, a node of the simulated network (as TSNet's messages
        name it): the junction the simulation inserted on the burst pipe is "the burst point on
        pipe <pipe>", a connector junction (:mod:`burstloc.sim.transient.tsnet_ready`) "the junction
        added between link <link> and node <node>"; the network's own nodes keep their names."""
        if node == self.metadata.get("burst_node"):
            return f"the burst point on pipe {self.pipe}"
        for connector in self.metadata.get("connectors") or ():
            if node == connector["junction"]:
                return (
                    f"the junction added between link {connector['link']} "
                    f"and node {connector['node']}"
                )
        return node

    def negative_pressure(self, shown: int | None = None) -> str | None:
        """``"burst on pipe P: negative pressure at ..."`` naming the nodes the solver reported
        below zero (:meth:`node_label`; with ``shown``, the first ``shown`` and a count of the
        rest), or ``None`` when none was."""
        negative = list(self.metadata.get("negative_pressure_nodes") or [])
        if not negative:
            return None
        named = negative if shown is None else negative[:shown]
        places = ", ".join(self.node_label(node) for node in named)
        more = f" and {len(negative) - len(named)} more" if len(named) < len(negative) else ""
        return f"burst on pipe {self.pipe}: negative pressure at {places}{more}"

    def resample(self, capture_interval: float, phase: float = 0.0) -> ScenarioResult:
        """Return the readings meters would transmit every ``capture_interval`` seconds.

        See :func:`burstloc.sim.scenarios.capture.resample` (sample-and-hold; an error if the
        interval is
        finer than the time step).
        """
        ticks, samples = capture.resample(self.time, self.heads, capture_interval, phase)
        meta = {**self.metadata, "capture_interval": float(capture_interval)}
        meta["capture_phase"] = float(phase)
        return replace(self, time=ticks, heads=samples, metadata=meta)

    def to_arrays(self) -> dict[str, np.ndarray]:
        """The NPZ layout: ``time``, ``heads``, ``junctions`` (str), ``metadata`` (JSON str)."""
        meta = {**self.metadata, "time_step": self.time_step}
        return {
            "time": np.asarray(self.time, dtype=np.float64),
            "heads": np.asarray(self.heads, dtype=np.float64),
            "junctions": np.asarray(self.junctions, dtype=np.str_),
            "metadata": np.asarray(json.dumps(meta, sort_keys=True)),
        }

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray]) -> ScenarioResult:
        """Inverse of :meth:`to_arrays`."""
        meta = json.loads(str(arrays["metadata"][()]))
        return cls(
            time=np.asarray(arrays["time"], dtype=np.float64),
            heads=np.asarray(arrays["heads"], dtype=np.float64),
            junctions=[str(j) for j in arrays["junctions"]],
            time_step=float(meta["time_step"]),
            metadata=meta,
        )

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the result as an NPZ file (atomically); readable with plain NumPy."""
        return write_npz(path, self.to_arrays())

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> ScenarioResult:
        """Read a result written by :meth:`save`."""
        with np.load(path, allow_pickle=False) as data:
            return cls.from_arrays({name: data[name] for name in data.files})


_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")


def output_path(directory: str | os.PathLike[str], result: ScenarioResult) -> Path:
    """Where the CLI writes a scenario: ``DIR/<network stem>_pipe-<pipe>.npz``."""
    stem = Path(str(result.metadata["network"])).stem
    return Path(directory) / f"{_UNSAFE.sub('_', stem)}_pipe-{_UNSAFE.sub('_', result.pipe)}.npz"
