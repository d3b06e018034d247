"""The live monitor against the batch decision rule, on the same noisy readings.

Usage: ``.venv/bin/python benches/bench_live_parity.py [--noise 0.01] [--seeds 0 1 2]
[--warm-up 90] [--detector cusum] [--example] [--cache-dir DIR]``.

paper15's 25 bursts (the paper's burst, or TSNet's example burst with ``--example``: 1 s
opening, coefficient 0.01), each preceded by ``--warm-up`` seconds of steady readings (a
monitor that has been running), every junction metered, 0.2 s capture, Gaussian noise of
``--noise`` m on every reading (one draw per seed and pipe), the configuration calibrated for
that noise. The same readings go, step by step, through :class:`BurstMonitor` (what runs live
and what ``burstloc evaluate`` now scores) and through the batch rule ``evaluate`` used before:
the calibrated bank over the whole readings, then ``rank_alarms`` on every alarm, with no
corroboration of a lone meter's alarm. Printed per seed: pipes named right by each, the bursts
where they differ, and the monitor's dismissed alarms; then the totals and their ratio.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
NETWORK = ROOT / "networks" / "paper15.inp"


def batch_rule(setup: Any, times: np.ndarray, values: np.ndarray, detector: str) -> str | None:
    """The pipe the batch rule names (the bank over every reading, then ``rank_alarms``)."""
    from burstloc.exceptions import InputError
    from burstloc.localize.decide import rank_alarms
    from burstloc.localize.interval import calibrated_bank

    cal = setup.config.for_interval(0.2)
    bank = calibrated_bank(detector, len(setup.meters), cal)
    alarms = bank.run(np.ascontiguousarray(values))
    if not alarms:
        return None
    try:
        decision = rank_alarms(
            "fused",
            setup.localizers_at(0.2),
            setup.meters,
            times,
            values,
            alarms,
            cal,
            "instantaneous",
        )
    except InputError:
        return None
    best = decision.ranking.best
    return None if best is None else best.pipe


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--noise", type=float, default=0.01)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--warm-up", type=float, default=90.0)
    parser.add_argument("--detector", default="cusum", choices=("cusum", "shewhart"))
    parser.add_argument("--example", action="store_true")
    parser.add_argument("--cache-dir", default=None)
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT / "python"))
    from burstloc import network as netmod
    from burstloc.experiments import paper
    from burstloc.experiments.calibrate import calibrate
    from burstloc.experiments.harness import Clock, capture_readings
    from burstloc.experiments.ranking import RankingSetup, first_decision
    from burstloc.live.monitor import BurstMonitor
    from burstloc.sim.scenarios.cache import DiskCache
    from burstloc.sim.scenarios.scenario import burst_scenarios
    from burstloc.sim.scenarios.sensors import SensorModel
    from burstloc.sim.transient import tsnet

    net = str(NETWORK)
    chosen = paper.TSNET_EXAMPLE_SCENARIO if args.example else paper.SCENARIO
    params = chosen.parameters()
    params["duration"] = 170.0
    pipes = netmod.pipe_names(netmod.load_network(net))
    scenarios = burst_scenarios(net, pipes, **params)
    cache = DiskCache(args.cache_dir) if args.cache_dir else True
    report = tsnet.simulate_many(scenarios, cache=cache, workers=1, progress=False)
    config = calibrate(net, capture_intervals=(0.2,), noise_sigma=max(args.noise, 1e-3))
    meters = list(config.meters)
    setup = RankingSetup.build(net, meters, [0.2], config)
    clock = Clock(0.2, 0.0, history=round(args.warm_up / 0.2))
    print(
        f"paper15, {len(pipes)} bursts ({'TSNet example' if args.example else 'paper'} burst), "
        f"{args.detector}, 0.2 s, noise {args.noise:g} m, {args.warm_up:g} s warm-up"
    )
    totals = {"monitor": 0, "batch": 0, "bursts": 0}
    cpu = {"monitor": 0.0, "batch": 0.0}
    for seed in args.seeds:
        sensor = SensorModel(noise_sigma=args.noise, seed=seed)
        right = {"monitor": 0, "batch": 0}
        differ, dismissed = [], 0
        for scenario, result in zip(scenarios, report.results, strict=True):
            assert result is not None
            times, values = capture_readings(
                result, clock, meters=meters, sensor=sensor, noise_key=scenario.pipe
            )
            started = time.process_time()
            monitor = BurstMonitor(
                net, config, capture_interval=0.2, detector=args.detector, localizer="fused"
            )
            decision = first_decision(monitor, times, values)
            cpu["monitor"] += time.process_time() - started
            live = None if decision is None or decision.ranking.best is None else decision.pipe
            started = time.process_time()
            batch = batch_rule(setup, times, values, args.detector)
            cpu["batch"] += time.process_time() - started
            right["monitor"] += live == scenario.pipe
            right["batch"] += batch == scenario.pipe
            dismissed += monitor.dismissed
            if live != batch:
                differ.append(f"{scenario.pipe}: monitor {live}, batch {batch}")
        print(
            f"seed {seed}: monitor {right['monitor']}/{len(pipes)}, batch rule "
            f"{right['batch']}/{len(pipes)}; dismissed {dismissed}; differ: "
            f"{'; '.join(differ) or 'none'}"
        )
        totals["monitor"] += right["monitor"]
        totals["batch"] += right["batch"]
        totals["bursts"] += len(pipes)
    n = totals["bursts"]
    print(
        f"total: monitor {totals['monitor']}/{n} ({100 * totals['monitor'] / n:.1f} %), batch "
        f"rule {totals['batch']}/{n} ({100 * totals['batch'] / n:.1f} %); CPU monitor / batch "
        f"= {cpu['monitor']:.1f} / {cpu['batch']:.1f} s (x{cpu['monitor'] / cpu['batch']:.1f})"
    )


if __name__ == "__main__":
    import os

    os.chdir(tempfile.gettempdir())
    main()
