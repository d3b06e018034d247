"""One TSNet transient run: a model written to an INP, TSNet's model of it, an event set up on
it, the initial steady state, and the MOC solved by burstloc's vectorized solver
(:mod:`burstloc.sim.transient.moc`) or TSNet's own ``MOCSimulator``; the meters' pressure heads
read back and checked finite. Bursts (:mod:`burstloc.sim.transient.tsnet`) and operations
(:mod:`burstloc.sim.events.operations`) both run here.

TSNet prints progress, warns on every time step and writes EPANET scratch files into the
working directory: :func:`isolated_run` holds a process-wide lock and a temporary working
directory for the duration of a run (TSNet is pure Python, threads would not help).
"""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from burstloc import network
from burstloc.constants import PRESSURE_NOISE
from burstloc.exceptions import ConfigError, SimulationError
from burstloc.sim.transient import _tsnet_compat, moc
from burstloc.sim.transient._tsnet_results import results_by_name
from burstloc.sim.transient.tsnet_elements import hold_valves

__all__ = ["MIN_STEPS", "TransientSettings", "isolated_run", "run_transient"]


#: TSNet fails on fewer time steps than this.
MIN_STEPS = 10


_TSNET_LOCK = threading.Lock()


@contextlib.contextmanager
def isolated_run() -> Iterator[str]:
    """Hold the TSNet lock and work in a fresh temporary directory (TSNet writes into cwd, and
    EPANET its scratch files: :func:`burstloc.network.epanet_workdir`)."""
    with _TSNET_LOCK, network.epanet_workdir("burstloc-tsnet-") as tmp:
        yield tmp


@dataclass(frozen=True)
class TransientSettings:
    """How a transient runs: wave speed (m/s), duration (s), requested time step (s, ``None`` =
    TSNet's largest), initial steady state engine, friction model and solver
    (:data:`~burstloc.sim.scenarios.scenario.SOLVERS`); ``pipe_speeds``, the wave speed (m/s)
    of the pipes it names in place of ``wave_speed`` (a perturbed truth,
    :mod:`burstloc.sim.scenarios.perturb`; TSNet discretises with each pipe's own)."""

    wave_speed: float
    duration: float
    time_step: float | None
    engine: str
    friction: str
    solver: str = "vectorized"
    pipe_speeds: Mapping[str, float] | None = None

    @classmethod
    def of(cls, scenario: Any) -> TransientSettings:
        """The settings of a scenario (anything with these five fields)."""
        return cls(
            scenario.wave_speed,
            scenario.duration,
            scenario.time_step,
            scenario.engine,
            scenario.friction,
            scenario.solver,
        )


def run_transient(
    wn: Any,
    meters: Sequence[str],
    inp: str,
    settings: TransientSettings,
    operate: Callable[[Any], None],
    *,
    where: str,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Write ``wn`` to ``inp``, run TSNet on it with ``operate(tm)`` setting up the event, and
    return ``(times, pressure heads of meters (T, M), time step)``. Call inside
    :func:`isolated_run` (TSNet writes into the working directory).

    Raises:
        ConfigError: a time step above TSNet's limit, or too few time steps.
        SimulationError: TSNet failed or produced non-finite heads.
    """
    tm = _run_tsnet(wn, inp, settings, operate, where, meters)
    steps = np.asarray(tm.simulation_timestamps, dtype=np.float64)
    solved = getattr(tm, "burstloc_heads", None)  # burstloc's solvers: the meters come first
    if solved is not None and solved[1][: len(meters)] == list(meters):
        heads = solved[0][:, : len(meters)]  # a view: no copy of the largest array
        if 2 * len(meters) < solved[0].shape[1]:  # a copy, so that the matrix can go
            heads = np.ascontiguousarray(heads)
    else:
        heads = np.column_stack([np.asarray(tm.get_node(j).head, np.float64) for j in meters])
    elevation = np.array([wn.get_node(j).elevation for j in meters], dtype=np.float64)
    if heads.shape[0] != steps.size:
        raise SimulationError(f"the transient simulation produced misshapen heads for {where}")
    broken = [j for j, ok in zip(meters, np.isfinite(heads).all(axis=0), strict=True) if not ok]
    if broken:
        raise SimulationError(
            f"the transient simulation produced non-finite heads for {where} at "
            f"{len(broken)} junction(s) ({', '.join(broken[:5])}"
            f"{', ...' if len(broken) > 5 else ''}){_negative(tm)}"
        )
    heads -= elevation  # (in the solver's matrix, once nothing reads its heads any more)
    return steps, heads, float(tm.time_step)


def _negative(tm: Any) -> str:
    """The junctions of TSNet's model with a negative initial pressure, as a message's end."""
    low = {
        name: float(node.head[0] - node.elevation)
        for name, node in tm.junctions()
        if node.head is not None and node.head[0] - node.elevation < -PRESSURE_NOISE
    }
    if not low:
        return ""
    named = ", ".join(f"{name!r} {p:.3g} m" for name, p in list(low.items())[:5])
    return f"; it cannot start from a negative pressure (EPANET's steady state): {named}"


def _run_tsnet(
    wn: Any,
    inp: str,
    settings: TransientSettings,
    operate: Callable[[Any], None],
    where: str,
    meters: Sequence[str] = (),
) -> Any:
    tsnet = _tsnet_compat.load()
    import wntr  # loaded with the network (burstloc.network), so known to be installed
    from tsnet.network.discretize import max_time_step

    # TSNet's Initializer sets this too; setting it first writes the INP's pressure-driven
    # demand options (required pressure, ...) into the file instead of WNTR's defaults.
    wn.options.hydraulic.demand_model = settings.engine
    wntr.network.write_inpfile(wn, inp, units=wn.options.hydraulic.inpfile_units)
    try:
        tm = tsnet.network.TransientModel(inp)
        tm.set_wavespeed(settings.wave_speed)
        if settings.pipe_speeds:  # those still pipes once prepared for TSNet
            pipes = set(tm.pipe_name_list)
            named = [p for p in settings.pipe_speeds if p in pipes]
            tm.set_wavespeed([settings.pipe_speeds[p] for p in named], pipes=named)
    except Exception as exc:
        raise SimulationError(f"TSNet could not load {where}: {exc}") from exc
    if settings.time_step is not None:
        limit = float(max_time_step(tm))
        if settings.time_step > limit:
            raise ConfigError(
                f"time_step {settings.time_step:g} s exceeds TSNet's stability limit "
                f"{limit:.5g} s for {where}"
            )
    try:
        tm.set_time(settings.duration, settings.time_step)
    except Exception as exc:
        raise SimulationError(f"TSNet could not discretize {where}: {exc}") from exc
    steps = int(settings.duration / tm.time_step)
    if steps < MIN_STEPS:  # TSNet's progress report divides by steps // 10
        raise ConfigError(
            f"duration {settings.duration:g} s is only {steps} time steps of "
            f"{tm.time_step:.5g} s; TSNet needs at least {MIN_STEPS}"
        )
    try:
        operate(tm)
        tm = _initialize(tsnet, tm, settings, where)
        hold_valves(tm)
        if settings.solver in ("vectorized", "numpy"):
            kernel = "rust" if settings.solver == "vectorized" else "numpy"
            return moc.solve(tm, settings.friction, kernel, first=meters)
        return tsnet.simulation.MOCSimulator(tm, results_obj="no", friction=settings.friction)
    except SimulationError as exc:
        raise SimulationError(f"{exc} ({where})") from exc
    except Exception as exc:
        raise SimulationError(f"TSNet failed for {where}: {type(exc).__name__}: {exc}") from exc


def _initialize(tsnet: Any, tm: Any, settings: TransientSettings, where: str = "") -> Any:
    """TSNet's ``Initializer``, its EPANET run over no duration: it reads EPANET's state at the
    start only, and the extended-period run it makes of the model's own duration solves the
    same first step and then every later one (L-TOWN's week at 5 min: 2 016 steps, 0.8 s per
    burst); the duration is restored before the transient runs. Where EPANET cannot solve the
    model pressure-driven it is solved demand-driven, as :func:`burstloc.network.steady_state`
    does (a :class:`~burstloc.exceptions.DemandDrivenWarning`, kept in the scenario's
    ``warnings``). For burstloc's own solvers it
    also runs over a period of two steps: it allocates six result series per pipe and two per
    node over the whole period, which only TSNet's solver fills (about 1 GB on L-TOWN's 32 554
    steps); burstloc's reads their first value, and the period is restored too. It reads EPANET's
    results by name (:func:`burstloc.sim.transient._tsnet_results.results_by_name`)."""
    times = tm.options.time
    duration, period = times.duration, tm.simulation_period
    times.duration = 0
    if settings.solver != "tsnet":
        tm.simulation_period = 2 * tm.time_step
    try:
        with results_by_name():
            try:
                return tsnet.simulation.Initializer(tm, 0.0, settings.engine)
            except Exception as exc:  # EPANET cannot solve it pressure-driven: demand-driven
                if settings.engine.upper() != "PDD" or type(exc).__name__ != "EpanetException":
                    raise
                network.warn_demand_driven(where or "the transient model", exc)
                return tsnet.simulation.Initializer(tm, 0.0, "DD")
    finally:
        times.duration, tm.simulation_period = duration, period
