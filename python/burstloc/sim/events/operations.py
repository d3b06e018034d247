"""Transients that are not bursts: valve and pump operations and demand steps, with TSNet.

A monitor that calls every transient a burst is useless in a control room: valves are operated,
pumps trip and start, large consumers switch on. An :class:`EventScenario` names one such event
on an asset of the network file:

==================  ========  ==========================================================
``kind``            asset     what happens (TSNet)
==================  ========  ==========================================================
``valve-closure``   a valve   from open to ``setting`` (fraction open; 0 = shut) in
                              ``operation_time`` s (``TransientModel.valve_closure``)
``valve-opening``   a valve   from shut to ``setting`` open (``valve_opening``)
``pump-trip``       a pump    from full speed to stopped (``pump_shut_off``)
``pump-start``      a pump    from stopped to full speed (``pump_start_up``)
``demand-step``     junction  its demand changes by ``demand_change`` m³/s (negative: a
                              consumer switching off) over ``operation_time`` s and stays
                              (``add_demand_pulse``, a pulse longer than the run)
==================  ========  ==========================================================

``operation_time`` tells a fast operation (1 s, the default) from a slow one (tens of
seconds). The result is a :class:`~burstloc.sim.scenarios.result.ScenarioResult` (the meters'
pressure
heads; metadata ``kind``, ``asset``, ``asset_nodes``, no ``pipe``), cached like a burst
(namespace :data:`SCHEMA`) and saved as NPZ. TSNet's valve opening and pump start need the
patches of :mod:`burstloc.sim.transient._tsnet_compat`.
"""

from __future__ import annotations

import math
import os
import re
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any

from burstloc import network
from burstloc._diagnostics import capture_diagnostics
from burstloc.constants import SCENARIO_DURATION, WAVE_SPEED
from burstloc.exceptions import ConfigError, NetworkError
from burstloc.sim.scenarios.cache import DiskCache, network_cache_key
from burstloc.sim.scenarios.result import ScenarioResult
from burstloc.sim.scenarios.scenario import DEFAULT_BURST_START, FRICTION_MODELS, check_solver
from burstloc.sim.transient.tsnet import cached, scenario_result
from burstloc.sim.transient.tsnet_ready import prepare_for_tsnet
from burstloc.sim.transient.tsnet_run import TransientSettings, isolated_run, run_transient
from burstloc.wave_speeds import WaveSpeeds

__all__ = ["EVENT_KINDS", "SCHEMA", "EventScenario", "event_output_path", "simulate_event"]

#: The kinds of non-burst event, and the kind of asset each acts on.
EVENT_KINDS = {
    "valve-closure": "valve",
    "valve-opening": "valve",
    "pump-trip": "pump",
    "pump-start": "pump",
    "demand-step": "junction",
}

#: Cache namespace; bump when a change changes what an event simulates (2: supply junctions
#: are fixed inflows, :func:`burstloc.sim.transient.tsnet_ready.add_supply_boundaries`).
SCHEMA = "event-scenario/2"

#: TSNet's closure constant ``m``: the opening changes linearly in time.
_LINEAR = 1.0


def _finite(name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{name} must be a number, got {value!r}")
    if not math.isfinite(float(value)):
        raise ConfigError(f"{name} must be finite, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class EventScenario:
    """One non-burst event (see the module's table).

    Attributes:
        network: path of the EPANET INP file.
        kind: one of :data:`EVENT_KINDS`.
        asset: the valve, pump or junction it acts on.
        start: when the operation begins, s (>= 0).
        operation_time: how long it takes, s (> 0 for a pump: TSNet divides by it).
        setting: a valve's final fraction open, in [0, 1) for a closure, (0, 1] for an
            opening; unused otherwise.
        demand_change: a demand step's change, m³/s (non-zero); unused otherwise.
        wave_speed, duration, engine, time_step, friction, solver, wave_speeds: as for a
            burst (:class:`~burstloc.sim.scenarios.scenario.BurstScenario`).

    Raises:
        ConfigError: a parameter out of range (named with its value).
    """

    network: str
    kind: str
    asset: str
    start: float = DEFAULT_BURST_START
    operation_time: float = 1.0
    setting: float = 0.0
    demand_change: float = 0.0
    wave_speed: float = WAVE_SPEED
    duration: float = SCENARIO_DURATION
    engine: str = "PDD"
    time_step: float | None = None
    friction: str = "steady"
    solver: str = "vectorized"
    wave_speeds: WaveSpeeds | None = None

    def __post_init__(self) -> None:
        put = object.__setattr__
        if self.wave_speeds is not None and not isinstance(self.wave_speeds, WaveSpeeds):
            raise ConfigError(f"wave_speeds must be WaveSpeeds, got {self.wave_speeds!r}")
        put(self, "wave_speeds", self.wave_speeds or None)
        put(self, "network", os.fspath(self.network))
        if self.kind not in EVENT_KINDS:
            raise ConfigError(f"event kind must be one of {list(EVENT_KINDS)}, got {self.kind!r}")
        if not isinstance(self.asset, str) or not self.asset:
            raise ConfigError(f"asset must be a non-empty name, got {self.asset!r}")
        for name in ("start", "operation_time", "setting", "demand_change", "wave_speed"):
            put(self, name, _finite(name, getattr(self, name)))
        put(self, "duration", _finite("duration", self.duration))
        if self.start < 0 or self.operation_time < 0:
            raise ConfigError(
                f"start and operation_time must be >= 0 s, got {self.start}, {self.operation_time}"
            )
        if EVENT_KINDS[self.kind] == "pump" and self.operation_time <= 0:
            raise ConfigError("a pump's operation_time must be > 0 s (TSNet divides by it)")
        if self.kind == "valve-closure" and not 0 <= self.setting < 1:
            raise ConfigError(f"a closure's setting must be in [0, 1), got {self.setting}")
        if self.kind == "valve-opening" and not 0 < self.setting <= 1:
            raise ConfigError(f"an opening's setting must be in (0, 1], got {self.setting}")
        if self.kind == "demand-step" and self.demand_change == 0:
            raise ConfigError("a demand step needs a non-zero demand_change (m³/s)")
        if self.wave_speed <= 0 or self.duration <= self.start:
            raise ConfigError(
                f"wave_speed must be > 0 and duration > start, got {self.wave_speed}, "
                f"{self.duration} s, {self.start} s"
            )
        put(self, "engine", str(self.engine).upper())
        if self.engine not in ("PDD", "DD"):
            raise ConfigError(f"engine must be 'PDD' or 'DD', got {self.engine!r}")
        if self.friction not in FRICTION_MODELS:
            raise ConfigError(f"friction must be one of {FRICTION_MODELS}, got {self.friction!r}")
        check_solver(self.solver, self.friction)
        if self.time_step is not None:
            put(self, "time_step", _finite("time_step", self.time_step))
            if self.time_step <= 0:  # type: ignore[operator]
                raise ConfigError(f"time_step must be > 0 s, got {self.time_step}")

    def parameters(self) -> dict[str, Any]:
        """Every field except the network path (the cache hashes the file's bytes); the
        ``"tsnet"`` solver is left out, so events cached before the field existed keep their
        keys (TSNet's results)."""
        params = asdict(self)
        del params["network"]
        if params["solver"] == "tsnet":
            del params["solver"]
        if self.wave_speeds is None:
            del params["wave_speeds"]
        else:  # keyed by the speeds, not by the file they came from
            params["wave_speeds"] = self.wave_speeds.to_json()
        return params

    @property
    def label(self) -> str:
        """``kind asset`` with its figures, e.g. ``valve-closure V16 to 0 in 1 s``."""
        if self.kind == "demand-step":
            what = f"{self.demand_change * 1000:+g} L/s"
        elif EVENT_KINDS[self.kind] == "valve":
            what = f"to {self.setting:g}"
        else:
            what = ""
        return " ".join(
            p for p in (self.kind, self.asset, what, f"in {self.operation_time:g} s") if p
        )


def simulate_event(
    scenario: EventScenario, cache: DiskCache | bool | None = True
) -> ScenarioResult:
    """Simulate one event (or load it from the cache; ``cache`` as for a burst).

    Raises:
        NetworkError: missing or malformed network, or an asset it does not have (or of
            another kind, or a junction without demand for a demand step).
        ConfigError: a time step above TSNet's limit, or too few time steps.
        SimulationError: TSNet failed, or produced non-finite heads.
        UnsteadyStartError: a junction's head moved more than
            :data:`~burstloc.sim.transient.steady.STEADY_TOLERANCE` before the event.
        SimulatorMissingError: the simulator (the ``sim`` extra) is not installed.
    """
    key = network_cache_key(SCHEMA, scenario.parameters(), scenario.network)
    return cached(scenario, key, cache, _simulate)


def _asset_nodes(wn: Any, scenario: EventScenario) -> list[str]:
    """The nodes where the event acts, after checking the asset is of the kind's type."""
    want = EVENT_KINDS[scenario.kind]
    where = f"{scenario.network}"
    if want == "junction":
        if scenario.asset not in network.junction_names(wn):
            raise NetworkError(f"no junction {scenario.asset!r} in {where}")
        demand = float(wn.get_node(scenario.asset).base_demand)
        if demand <= 0:
            raise NetworkError(
                f"junction {scenario.asset!r} of {where} has no base demand: TSNet scales a "
                "junction's demand, so a demand step needs one"
            )
        return [scenario.asset]
    names = wn.valve_name_list if want == "valve" else wn.pump_name_list
    if scenario.asset not in names:
        raise NetworkError(f"no {want} {scenario.asset!r} in {where} (it has {list(names)})")
    link = wn.get_link(scenario.asset)
    return [link.start_node_name, link.end_node_name]


def _operate(scenario: EventScenario, wn: Any) -> Any:
    """The TSNet call that sets the event up on a transient model."""
    s = scenario
    rule = [s.operation_time, s.start, s.setting, _LINEAR]

    def operate(tm: Any) -> None:
        if s.kind == "valve-closure":
            tm.valve_closure(s.asset, rule)
        elif s.kind == "valve-opening":
            tm.valve_opening(s.asset, rule)
        elif s.kind == "pump-trip":
            tm.pump_shut_off(s.asset, [s.operation_time, s.start, 0.0, _LINEAR])
        elif s.kind == "pump-start":
            tm.pump_start_up(s.asset, [s.operation_time, s.start, 1.0, _LINEAR])
        else:  # a pulse that ramps over operation_time and lasts past the end of the run
            multiplier = s.demand_change / float(wn.get_node(s.asset).base_demand)
            lasting = 2 * (s.duration + s.operation_time)
            tm.add_demand_pulse(s.asset, [lasting, s.start, s.operation_time, multiplier])

    return operate


def _simulate(scenario: EventScenario) -> ScenarioResult:
    started = time.perf_counter()
    source = os.path.abspath(scenario.network)
    with isolated_run() as tmp, capture_diagnostics() as diag:
        wn = network.as_network(source, diagnostics=True).editable()  # the events change it
        nodes = _asset_nodes(wn, scenario)
        meters = network.junction_names(wn)
        given = scenario.wave_speeds
        speeds = given.differing(wn, scenario.wave_speed) if given else {}
        prepared = prepare_for_tsnet(wn, keep=(scenario.asset,))
        transient = run_transient(
            wn,
            meters,
            os.path.join(tmp, "event.inp"),
            replace(
                TransientSettings.of(scenario),
                pipe_speeds=speeds or None,
            ),
            _operate(scenario, wn),
            where=f"{scenario.label} of {scenario.network}",
        )
    specific = {"event": scenario.kind, "asset_nodes": nodes, "label": scenario.label}
    run = (prepared, started, diag, SCHEMA)
    return scenario_result(scenario, scenario.start, (*transient, meters), run, specific)


_UNSAFE = re.compile(r"[^A-Za-z0-9._-]")


def event_output_path(directory: str | os.PathLike[str], scenario: EventScenario) -> Path:
    """Where the CLI writes an event: ``DIR/<network stem>_<kind>-<asset>.npz``."""
    stem = _UNSAFE.sub("_", Path(scenario.network).stem)
    return Path(directory) / f"{stem}_{scenario.kind}-{_UNSAFE.sub('_', scenario.asset)}.npz"
