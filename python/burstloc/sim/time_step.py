"""The time step TSNet will use for a burst, and the one to ask for.

:func:`expected_time_step` reproduces TSNet's discretisation without running it;
:func:`capture_time_step` is the rule ``burstloc study`` and ``burstloc evaluate`` apply when no
step is requested: TSNet's own, or half the finest capture interval where TSNet's is coarser.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from burstloc import network
from burstloc.exceptions import NetworkError
from burstloc.sim.scenario import BurstScenario
from burstloc.sim.tsnet_ready import prepare_for_tsnet, transient_model

__all__ = ["capture_time_step", "expected_time_step", "with_capture_time_step"]


def expected_time_step(scenario: BurstScenario) -> float:
    """The time step (s) TSNet will use for ``scenario``, without running TSNet.

    TSNet's discretisation is arithmetic on the pipe lengths of the split network (of its
    transient-ready model with ``min_pipe_length``, :func:`~burstloc.sim.tsnet_ready.
    transient_model`, prepared for TSNet): each pipe
    gets ``N = floor(L / (a dt))`` reaches for the requested step ``dt`` (default: the Courant
    limit ``min L / (2 a)``), and the step becomes ``sum(phi^2) / sum(phi)`` with
    ``phi = L / (a N)`` (its wave-speed adjustment). This reproduces it, so a caller can choose
    ``time_step`` before simulating (e.g. finer than a capture interval).

    Raises:
        NetworkError: the network or pipe cannot be read.
    """
    wn = network.load_network(scenario.network)
    network.require_pipe(wn, scenario.pipe)
    model, pipe, position, _ = transient_model(wn, scenario)
    split = network.split_pipe(model, pipe, position)
    prepare_for_tsnet(split.network)  # the pipes TSNet will see
    lengths = [float(pipe.length) for _, pipe in split.network.pipes()]
    travel = np.array(lengths) / scenario.wave_speed
    dt = float(travel.min() / 2.0) if scenario.time_step is None else float(scenario.time_step)
    reaches = np.floor(travel / dt)
    if np.any(reaches < 1):
        return dt  # TSNet refuses such a step; _run_tsnet reports it
    phi = travel / reaches
    return float(np.sum(phi**2) / np.sum(phi))


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
        expected = expected_time_step(replace(scenario, time_step=None))
    except NetworkError:
        return None  # an unknown pipe: its simulation fails and names it
    return None if expected <= finest_interval else finest_interval / 2


def with_capture_time_step(
    scenarios: Sequence[BurstScenario], finest_interval: float
) -> list[BurstScenario]:
    """``scenarios`` with the time step of :func:`capture_time_step` (their own, if set)."""
    return [
        replace(s, time_step=capture_time_step(s, finest_interval, s.time_step)) for s in scenarios
    ]
