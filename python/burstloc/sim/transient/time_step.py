"""The time step TSNet will use for a burst, and the one to ask for.

:func:`expected_time_step` reproduces TSNet's discretisation without running it;
:func:`capture_time_step` is the rule ``burstloc study`` and ``burstloc evaluate`` apply when no
step is requested: TSNet's own, or half the finest capture interval where TSNet's is coarser.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from copy import deepcopy
from dataclasses import replace
from typing import Any

import numpy as np

from burstloc import network
from burstloc.exceptions import NetworkError
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.intact import IntactNetwork, intact
from burstloc.sim.transient.tsnet_ready import pipe_speeds, prepare_for_tsnet

__all__ = ["capture_time_step", "expected_time_step", "with_capture_time_step"]

#: Relative margin kept below a capture interval for the rounding of TSNet's step.
FLOAT_MARGIN = 1e-9


def expected_time_step(scenario: BurstScenario) -> float:
    """The time step (s) TSNet will use for ``scenario``, without running TSNet.

    TSNet's discretisation is arithmetic on the pipes' travel times ``L / a`` in the split
    network (of its transient-ready model with ``min_pipe_length``, :func:`~burstloc.sim.
    transient.tsnet_ready.transient_model`, prepared for TSNet; each pipe at its own speed with
    ``wave_speeds``): each pipe gets ``N = floor(L / (a dt))`` reaches for the requested step
    ``dt`` (default: the Courant limit ``min L / (2 a)``), and the step becomes
    ``sum(phi^2) / sum(phi)`` with ``phi = L / (a N)`` (its wave-speed adjustment). This
    reproduces it, so a caller can choose ``time_step`` before simulating (e.g. finer than a
    capture interval). The network is prepared for TSNet once (:func:`_prepared_pipes`); the
    burst pipe is then cut in two at ``position`` (a split's preparation is the same but for
    those halves; where the preparation does not keep the burst pipe a pipe, the split
    network is prepared as the simulation will).

    Raises:
        NetworkError: the network or pipe cannot be read.
    """
    kept = intact(scenario.network)
    network.require_pipe(kept.wn, scenario.pipe)
    model, pipe, position, prepared = kept.transient_model(scenario)
    lengths, connectors = kept.step(
        ("prepared pipes", scenario.min_pipe_length), lambda: _prepared_pipes(model)
    )
    if pipe in lengths:
        whole = lengths[pipe]
        halves = (position * whole, (1.0 - position) * whole)
        # connectors are as long as the shortest pipe, a half of the split one included
        pieces = {
            n: min(length, *halves) if n in connectors else length for n, length in lengths.items()
        }
        pieces |= {pipe: halves[0], f"{pipe} ": halves[1]}
        aliases = {f"{pipe} ": pipe}
    else:  # a check-valve pipe made a valve, ...: as the simulation will see it
        split = network.split_pipe(model, pipe, position)
        prepare_for_tsnet(split.network)
        pieces = {name: float(p.length) for name, p in split.network.pipes()}
        aliases = {split.second_pipe: pipe}
    speeds = pipe_speeds(scenario, kept.wn, list(pieces), prepared, aliases)
    length = np.array(list(pieces.values()))
    speed = np.array([speeds.get(n, scenario.wave_speed) for n in pieces])
    # in TSNet's order of operations (tsnet.network.discretize), to the last bit
    dt = float(np.min(length / (2.0 * speed))) if scenario.time_step is None else scenario.time_step
    reaches = np.floor(length / (speed * dt))
    if np.any(reaches < 1):
        return dt  # TSNet refuses such a step; _run_tsnet reports it
    phi = length / speed / reaches
    return float(np.sum(phi**2) / np.sum(phi))


def _prepared_pipes(model: Any) -> tuple[dict[str, float], frozenset[str]]:
    """Each pipe's length (m) in a copy of ``model`` prepared for TSNet
    (:func:`~burstloc.sim.transient.tsnet_ready.prepare_for_tsnet`), and which are its
    connectors."""
    copy = deepcopy(model)
    preparation = prepare_for_tsnet(copy)
    connectors = frozenset(c.pipe for c in preparation.connectors)
    return {name: float(p.length) for name, p in copy.pipes()}, connectors


def capture_time_step(
    scenario: BurstScenario, finest_interval: float, requested: float | None = None
) -> float | None:
    """The time step to request for ``scenario`` when its results are read every
    ``finest_interval`` s or coarser: ``requested`` if given; else TSNet's own (``None``) when
    it is no coarser than that interval, and half the interval otherwise (a capture needs
    simulated samples at least as fine as its interval; half of it keeps TSNet's wave-speed
    adjustment, which can lengthen a requested step by up to 50 %, below the interval).
    The rule of ``burstloc study`` and ``burstloc evaluate``.
    """
    if requested is not None:
        return requested
    try:
        if _surely_finer(scenario, finest_interval):
            return None
        expected = expected_time_step(replace(scenario, time_step=None))
    except NetworkError:
        return None  # an unknown pipe: its simulation fails and names it
    return None if expected <= finest_interval else finest_interval / 2


def _surely_finer(scenario: BurstScenario, finest_interval: float) -> bool:
    """Whether TSNet's own step for ``scenario`` (:func:`expected_time_step`) is surely below
    ``finest_interval``, seen without splitting the pipe and preparing the model for TSNet
    (0.35 s a burst on L-TOWN, in the process that sets the steps of a whole sweep).

    TSNet's step is ``sum(phi^2) / sum(phi)`` with every ``phi = L / (a N)`` below twice the
    requested step ``min L / (2 a)`` (``N = floor(L / (a dt)) > L / (2 a dt)``), so below the
    travel time ``L / a`` of any pipe of the prepared model. A pipe of the transient-ready model
    other than the burst's is one of them, as long as it is, in every preparation for TSNet
    (:func:`~burstloc.sim.transient.tsnet_ready.prepare_for_tsnet`), neither removed nor made a
    valve:
    open, without a check valve, named by no control and joined to no tank (the links EPANET
    may close at the start)."""
    kept = intact(scenario.network)
    _, pipe, _, _ = kept.transient_model(scenario)
    shortest = kept.step(
        ("lasting pipes", scenario.min_pipe_length),
        lambda: _lasting(kept, scenario.min_pipe_length),
    )
    travel = min((length for length, name in shortest if name != pipe), default=math.inf)
    return travel / scenario.wave_speed < finest_interval * (1.0 - FLOAT_MARGIN)


def _lasting(kept: IntactNetwork, min_pipe_length: float | None) -> list[tuple[float, str]]:
    """``(length, name)`` of the two shortest pipes of the transient-ready model that every
    preparation for TSNet keeps as they are (:func:`_surely_finer`)."""
    model, _ = kept.transient_ready(min_pipe_length)
    controlled = {obj.name for _, control in model.controls() for obj in control.requires()}
    tanks = set(model.tank_name_list)
    lasting = [
        (float(pipe.length), name)
        for name, pipe in model.pipes()
        if pipe.initial_status.name == "Open"
        and not pipe.check_valve
        and name not in controlled
        and not {pipe.start_node_name, pipe.end_node_name} & tanks
    ]
    return sorted(lasting)[:2]


def with_capture_time_step(
    scenarios: Sequence[BurstScenario], finest_interval: float
) -> list[BurstScenario]:
    """``scenarios`` with the time step of :func:`capture_time_step` (their own, if set)."""
    return [
        replace(s, time_step=capture_time_step(s, finest_interval, s.time_step)) for s in scenarios
    ]
