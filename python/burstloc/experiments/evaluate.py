"""Burst every pipe, stream the meters' readings, localize, and score (paper section V).

For a network and one or more runs (detector x capture interval x parameters x mode; built in
:mod:`burstloc.experiments.runs`):

1. one burst scenario per pipe is simulated (or loaded from the cache) with the
   :data:`burstloc.experiments.paper.SCENARIO` choices, long enough for every run to see
   ``2 x interval`` readings after the burst;
2. each scenario is sampled at the run's capture interval at ``phases`` clock offsets and
   replayed through the real-time loop (:class:`burstloc.live.paper_locator.BurstLocator`):
   the first window whose changes make the rules name a pipe decides (the paper's single
   localization attempt); no decision means "not located", never a guess;
3. a prediction is correct when it names the burst pipe; accuracy = correct / pipes (eq. 4).

Every attempt is captured, decided and counted by :mod:`burstloc.experiments.harness`, the same
code ``burstloc study`` scores with; :mod:`burstloc.experiments.scoring` runs them.

**Phases.** Phase ``k`` of ``N`` starts the capture clock, and with it the window grid, ``k / N``
of one capture interval (``phase_span="capture"``, the default) or of one localization window,
``interval x capture interval`` (``phase_span="window"``: every alignment of the windows to the
burst), earlier relative to the burst
(:func:`~burstloc.experiments.harness.readings_at_offset`). Accuracy is reported at phase 0
(the per-pipe tables) and as mean, min and max over the phases. The time to localize is the
decision time (the timestamp of the newest reading of the deciding window) minus the
burst start; its median is taken over every located attempt, all phases.

**Localizers.** ``RunSpec.localizer`` is ``"paper"`` (the rules above, the default) or one of
the ranking localizers ``"arrival"``, ``"signature"``, ``"fused"``
(:mod:`burstloc.localize.arrival`, :mod:`burstloc.localize.signature`,
:mod:`burstloc.localize.fused`). These run the Rust detector bank with a calibrated
configuration (:mod:`burstloc.experiments.calibrate`; computed for the network when none is
given: no hand tuning), build the evidence from its alarms at the localizer's decision time
(:func:`burstloc.localize.decide.rank_alarms`) and rank every pipe; the prediction is the
best-ranked pipe, and top-1 / top-3 accuracy are reported (for the paper's rules, which name
one pipe, top-3 equals top-1). The arrival and fused localizers also give the burst's position on
the named pipe; its error is the network distance to the simulated burst point
(:mod:`burstloc.experiments.position`), reported as mean and 90th percentile over every attempt.
``RunSpec.meter_model`` chooses instantaneous samples (the
paper's) or interval-averaged readings (:func:`burstloc.sim.scenarios.capture.capture`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from burstloc.exceptions import ConfigError
from burstloc.experiments import paper
from burstloc.experiments.harness import Attempt
from burstloc.experiments.outcome import Evaluation, RunResult
from burstloc.experiments.position import (
    PositionScorer,
    wave_travel,
)
from burstloc.experiments.ranking import RankingSetup
from burstloc.experiments.region_score import score_regions
from burstloc.experiments.runs import (
    RunSpec,
    phase_offsets,
    required_duration,
)
from burstloc.experiments.scoring import check_results, score_runs
from burstloc.experiments.truth import Hearing, check_truth
from burstloc.sim.scenarios.perturb import TruthPerturbation

if TYPE_CHECKING:
    from burstloc.localize.config import Calibration
    from burstloc.network import NetworkSource
    from burstloc.sim.scenarios.result import ScenarioResult
    from burstloc.sim.scenarios.sensors import SensorModel
    from burstloc.sim.signatures.burst_size import BurstFlow
    from burstloc.wave_speeds import WaveSpeeds

__all__ = [
    "DEFAULT_LOCALIZER",
    "Evaluation",
    "RunResult",
    "evaluate",
]

#: ``burstloc evaluate``'s localizer: the fused one, ahead of the paper's rules at every capture
#: interval in ``burstloc study`` (docs/study/report.md).
DEFAULT_LOCALIZER = "fused"

KEPT_PIPES = 10
"""Best pipes a streamed evaluation keeps of each decision's ranking (the tables read three)."""


def evaluate(
    network: NetworkSource,
    runs: Sequence[RunSpec],
    *,
    pipes: Sequence[str] | None = None,
    phases: int = 5,
    phase_span: str = "capture",
    scenario: paper.ScenarioConfig = paper.SCENARIO,
    cache: Any = True,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    config: Calibration | None = None,
    meters: Sequence[str] | None = None,
    time_step: float | None = None,
    noise: float | None = None,
    noise_seed: int = 0,
    keep_heads: bool = True,
    burst_flow: float | BurstFlow | None = None,
    truth: TruthPerturbation | None = None,
    wave_speeds: WaveSpeeds | None = None,
) -> Evaluation:
    """Run the experiment: simulate (cached), stream, localize and score every run.

    With ``keep_heads=False`` each burst is scored as its simulation arrives and only its
    first time step is kept (in ``Evaluation.results``), and each attempt only its decisions'
    :data:`KEPT_PIPES` best pipes (:meth:`~burstloc.experiments.harness.Attempt.compact`):
    memory no longer grows with the number of pipes (a 905-pipe network at a 6.8 ms step holds
    about 200 MB of heads per burst, a ranking of every pipe about 160 KB per attempt). With
    ``meters`` and no run of the paper's rules, the simulations then record the meters' heads
    only (the scenarios' ``recorded``): L-TOWN's 33 meters at a 5 ms step are 8 MB per burst
    where its 782 junctions are 190 MB, in the worker and again on their way to the scoring.
    The scores are the same; what reads a burst's heads afterwards (plots, the event
    classifier) needs the default.

    ``time_step`` is TSNet's requested time step (s); ``None`` applies the rule of ``burstloc
    study`` (:func:`burstloc.sim.transient.time_step.capture_time_step`): TSNet's own step, or half
    the finest
    capture interval where TSNet's would be coarser. The JSON's ``scenario`` records it.

    ``config`` is the calibration the ranking localizers' detector bank uses (runs with
    ``localizer != "paper"``); without one the network is calibrated here. ``meters`` are the
    junctions that carry meters for the ranking localizers (default: every junction; e.g. a
    meter file's, :class:`burstloc.sim.placement.methods.MeterSet`); the paper's rules read every
    junction, as in the paper.

    With ``pipes=None`` (every pipe) the pipes closed in the network file are left out, and
    said in the warnings.

    ``noise`` is the meters' Gaussian noise (m, standard deviation) added to every reading,
    drawn with ``noise_seed``: ``None`` (default) adds the calibrated noise of each meter
    (the configuration's ``noise_sigma``, what the monitor was calibrated for) to the ranking
    localizers' readings and none to the paper's rules (the paper's experiment is noiseless);
    a number adds that noise to every run's readings, ``0`` none. The JSON's ``scenario``
    records it.

    ``burst_flow`` (m³/s, or a :class:`~burstloc.sim.signatures.burst_size.BurstFlow`: a share of
    the network's demand) sizes every burst by its flow instead of the scenario's coefficient:
    each pipe's coefficient draws it at its burst point's pressure before it opens
    (:mod:`burstloc.sim.signatures.burst_size`). The JSON's ``scenario`` records each burst's
    nominal flow either way (``burst_flows_lps``, per pipe) and, sized by flow,
    ``burst_flow_lps``, how it was chosen (``burst_sizing``, e.g. "5 % of the network's demand,
    at most 5 L/s") and each pipe's coefficient (``burst_coeffs``) in place of
    ``burst_coeff``.

    ``truth`` simulates the truth the meters hear on a perturbed network while the localizers
    keep the model (:mod:`burstloc.sim.scenarios.perturb`, :mod:`burstloc.experiments.truth`);
    the JSON's ``scenario`` records it (``truth``) and, with a silent meter, which meter fell
    silent for each burst (``truth_silent_meters``). ``wave_speeds``: pipes of their own wave
    speed in the simulation and in a calibration made here (a ``config`` keeps its own model);
    the JSON's ``scenario`` records them (``wave_speeds``).

    Raises:
        NetworkError: missing or malformed network, unknown pipe, a named pipe that is closed.
        ConfigError: no runs, bad phases, a time step that is not a positive number of seconds,
            or a capture interval finer than the simulation's time step; a bad burst flow; a
            silent meter with the paper's rules (they have no missing-reading policy).
        SimulationError: a burst could not be simulated.
    """
    from burstloc import inp
    from burstloc import network as netmod
    from burstloc.sim.scenarios.scenario import burst_scenarios
    from burstloc.sim.signatures.burst_size import sized_scenarios
    from burstloc.sim.transient import tsnet as simulate
    from burstloc.sim.transient.time_step import with_capture_time_step

    if not runs:
        raise ConfigError("no runs to evaluate")
    check_truth(truth, [spec.localizer for spec in runs])
    for spec in runs:
        phase_offsets(spec, phases, phase_span)  # validates phases and span
    read = netmod.as_network(network)
    path, wn = read.path, read.model
    graph = netmod.flow_direction_graph(wn)
    chosen = inp.choose_pipes(netmod.pipe_names(wn), pipes, path)

    warnings: list[str] = []
    closed = netmod.closed_pipes(wn)
    if pipes is None and closed:  # every pipe: those closed in the file carry no water
        chosen = [p for p in chosen if p not in closed]
        warnings.append(
            f"{len(closed)} pipe(s) closed in the network file, not burst: {', '.join(closed)}"
        )
    for pipe in chosen:  # a pipe named closed: said before anything is simulated
        netmod.require_pipe(wn, pipe, open_only=True)
    params: dict[str, Any] = scenario.parameters()
    travel = wave_travel(wn, float(params["wave_speed"]))
    needed = max(required_duration(s, scenario.burst_start, travel) for s in runs)
    if params["duration"] is None:
        params["duration"] = float(math.ceil(needed - 1e-9))
    elif params["duration"] + 1e-9 < needed:
        worst = max(runs, key=lambda s: required_duration(s, scenario.burst_start, travel))
        raise ConfigError(
            f"the scenario simulates {params['duration']:g} s but the run "
            f"{worst.detector.kind} at {worst.capture_interval:g} s with localization interval "
            f"{worst.localization_interval} needs {needed:g} s (2 x interval readings after "
            f"the burst at {scenario.burst_start:g} s, whatever the phase)"
        )
    params["time_step"] = time_step
    finest = min(spec.capture_interval for spec in runs)
    scenarios = with_capture_time_step(burst_scenarios(read, chosen, **params), finest)
    scenarios, sizes = sized_scenarios(scenarios, burst_flow, read)
    if burst_flow is not None:
        del params["burst_coeff"]
        params["burst_flow_lps"] = round(sizes[0].flow_lps, 6)
        params["burst_sizing"] = (
            burst_flow.describe()
            if not isinstance(burst_flow, (int, float))
            else f"{1000 * burst_flow:g} L/s"
        )
        params["burst_coeffs"] = {s.pipe: s.coeff for s in sizes}
    params["burst_flows_lps"] = {s.pipe: round(s.flow_lps, 3) for s in sizes}
    if truth is not None and truth.active:
        scenarios = [replace(s, truth=truth) for s in scenarios]
        params["truth"] = truth.to_dict()
    if wave_speeds:
        scenarios = [replace(s, wave_speeds=wave_speeds) for s in scenarios]
        params["wave_speeds"] = wave_speeds.to_json()
    ranked = [spec for spec in runs if spec.localizer != "paper"]
    if meters and not keep_heads and len(ranked) == len(runs):  # only the meters are read
        metered = inp.check_meters(meters, netmod.junction_names(wn), path)
        scenarios = [replace(s, recorded=tuple(metered)) for s in scenarios]
    scoring: dict[str, Any] = {}  # the ranking setup and sensors, made from the first result

    def prepare(first: ScenarioResult) -> None:
        setup = None
        if ranked:
            junctions = list(first.junctions)
            metered = inp.check_meters(meters, junctions, path) if meters else junctions
            intervals = sorted({spec.capture_interval for spec in ranked})
            setup = RankingSetup.build(
                read, metered, intervals, config, wave_speeds, float(params["wave_speed"])
            )
        scoring.update(setup=setup, sensors=_sensors(noise, noise_seed, setup))
        heard_by = None if setup is None else setup.meters
        scoring["hear"] = Hearing(truth or TruthPerturbation(), wn, heard_by)

    streamed: dict[str, dict[RunSpec, list[Attempt]]] = {}

    def score_and_drop(scenario: Any, result: ScenarioResult) -> ScenarioResult:
        """Streaming: check and score one burst as it arrives; keep its first step only."""
        check_results(runs, [result], phases, phase_span)
        if not scoring:
            prepare(result)
        scored = score_runs(
            runs,
            {result.pipe: scoring["hear"](result)},
            [result.pipe],
            graph,
            scoring["setup"],
            phases,
            phase_span,
            scoring["sensors"],
        )
        streamed[result.pipe] = {
            spec: [a.compact(KEPT_PIPES) for a in by_pipe[result.pipe]]
            for spec, by_pipe in scored.items()
        }
        # copies: a slice would keep the whole arrays alive
        return replace(result, time=result.time[:1].copy(), heads=result.heads[:1].copy())

    report = simulate.simulate_many(
        scenarios,
        cache=cache,
        workers=workers,
        scheduler=scheduler,
        progress=progress,
        shrink=None if keep_heads else score_and_drop,
    )
    if report.failures:
        from burstloc.exceptions import SimulationError

        raise SimulationError("; ".join(report.failure_lines()))
    results = {s.pipe: r for s, r in zip(scenarios, report.results, strict=True) if r is not None}
    if keep_heads:
        check_results(runs, list(results.values()), phases, phase_span)

    warnings += [w for r in results.values() if (w := r.negative_pressure()) is not None]
    endpoints = {p: r.true_endpoints for p, r in results.items()}
    if not scoring:
        prepare(next(iter(results.values())))
    setup, sensors = scoring["setup"], scoring["sensors"]
    params["noise"] = _noise_record(noise, setup)
    params["noise_seed"] = noise_seed
    hear = scoring["hear"]
    if keep_heads:
        heard = {p: hear(r) for p, r in results.items()}
        attempts = score_runs(runs, heard, chosen, graph, setup, phases, phase_span, sensors)
    else:  # scored as they arrived; in the order of the pipes
        attempts = {spec: {p: streamed[p][spec] for p in chosen} for spec in runs}
    if hear.truth.silent_meter is not None:
        params["truth_silent_meters"] = {p: hear.silent[p] for p in chosen}
    scorer = PositionScorer(wn, {p: results[p] for p in chosen})
    lengths = {p: float(wn.get_link(p).length) for p in chosen}
    out = []
    for spec in runs:
        positions = scorer.score(attempts[spec])
        regions = score_regions(
            attempts[spec], scorer.points, lengths, positions, error_of=scorer.error
        )
        offsets = phase_offsets(spec, phases, phase_span)
        out.append(
            RunResult(
                spec, chosen, endpoints, offsets, attempts[spec], scorer.points, positions, regions
            )
        )
    meters_used = [] if setup is None else list(setup.meters)
    return Evaluation(
        path, out, params, phase_span, warnings, results, graph, meters_used, setup=setup
    )


def _sensors(
    noise: float | None, seed: int, setup: RankingSetup | None
) -> dict[str, SensorModel | None]:
    """The sensor model of the paper's rules and of the ranking localizers (see
    :func:`evaluate`'s ``noise``)."""
    from burstloc.sim.scenarios.sensors import SensorModel

    if noise is not None:
        sensor = SensorModel(noise_sigma=noise, seed=seed) if noise > 0 else None
        return {"paper": sensor, "ranking": sensor}
    if setup is None:
        return {"paper": None, "ranking": None}
    calibrated = SensorModel(seed=seed, meter_sigma=setup.config.noise_sigma)
    return {"paper": None, "ranking": calibrated if calibrated.enabled else None}


def _noise_record(noise: float | None, setup: RankingSetup | None) -> dict[str, Any]:
    """The JSON record of the readings' noise: m per run kind, per meter where calibrated."""
    if noise is not None:
        return {"paper": noise, "ranking": noise}
    ranking = None if setup is None else dict(setup.config.noise_sigma)
    return {"paper": 0.0, "ranking": ranking}
