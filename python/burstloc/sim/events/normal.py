"""A day of normal operation: the meters' background pressure, with no burst and no event.

Demand follows a daily pattern, so pressure drifts slowly all day; a monitor must not call that
a burst. :func:`normal_day` runs an EPANET extended-period simulation (through WNTR,
pressure-driven demand) with every junction's demand scaled by :data:`DIURNAL` (hourly
multipliers of a residential day: a night low, a morning and an evening peak; mean 1), samples
the meters' pressure heads at the capture interval (linear between the hydraulic steps, which
is what the slow part is: no transient solver is needed) and adds Gaussian sensor noise
(:class:`burstloc.sim.scenarios.sensors.SensorModel`). For tests, benchmarks and the monitor's soak.

What EPANET warns (e.g. WNTR raising a required pressure below EPANET's lower limit of 0.1 in
the file's pressure unit, as for EPANET's Net1, which sets none) is kept out of the terminal,
as for the steady state (:func:`burstloc.network.steady_state`): a caller's
:func:`burstloc._diagnostics.capture_diagnostics` records it.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from burstloc import network
from burstloc._diagnostics import capture_diagnostics
from burstloc.exceptions import ConfigError
from burstloc.inp import check_meters
from burstloc.sim.scenarios.sensors import SensorModel

__all__ = ["DIURNAL", "HYDRAULIC_STEP", "normal_day"]

#: Hourly demand multipliers from midnight (mean 1.0).
DIURNAL = (
    0.55, 0.45, 0.40, 0.40, 0.45, 0.60, 0.95, 1.45, 1.55, 1.35, 1.20, 1.15,
    1.15, 1.10, 1.05, 1.05, 1.10, 1.25, 1.45, 1.50, 1.35, 1.10, 0.85, 0.65,
)  # fmt: skip

#: Seconds between the hydraulic solutions of the extended-period run.
HYDRAULIC_STEP = 300


def normal_day(
    network_path: network.NetworkSource,
    *,
    capture_interval: float,
    noise_sigma: float = 0.01,
    hours: float = 24.0,
    meters: Sequence[str] | None = None,
    pattern: Sequence[float] = DIURNAL,
    seed: int = 0,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The meters' readings over ``hours`` of normal operation: ``(times (T,), heads (T, M))``.

    ``meters`` default to every junction (INP order). Readings every ``capture_interval`` s from
    0, pressure head in metres, plus noise of ``noise_sigma`` m drawn from ``seed``.

    Raises:
        ConfigError: a non-positive interval or duration, a bad pattern or noise level.
        NetworkError: a missing or malformed network, or a meter that is not a junction.
    """
    if not (math.isfinite(capture_interval) and capture_interval > 0):
        raise ConfigError(f"capture_interval must be > 0 s, got {capture_interval}")
    if not (math.isfinite(hours) and 0 < hours <= 24 * 7):
        raise ConfigError(f"hours must be in (0, 168], got {hours}")
    multipliers = [float(m) for m in pattern]
    if not multipliers or not all(math.isfinite(m) and m >= 0 for m in multipliers):
        raise ConfigError("the demand pattern must be finite multipliers >= 0")
    import wntr

    read = network.as_network(network_path)
    wn = read.editable()  # its demands and times are changed for the run
    junctions = network.junction_names(wn)
    names = check_meters(junctions if meters is None else meters, junctions, read.path)
    wn.add_pattern("burstloc_diurnal", multipliers)
    for name in network.junction_names(wn):
        for demand in wn.get_node(name).demand_timeseries_list:
            demand.pattern_name = "burstloc_diurnal"
    duration = math.ceil(hours * 3600)
    wn.options.time.duration = duration
    wn.options.time.hydraulic_timestep = HYDRAULIC_STEP
    wn.options.time.report_timestep = HYDRAULIC_STEP
    wn.options.time.pattern_timestep = 3600
    wn.options.hydraulic.demand_model = "PDD"
    # EPANET's scratch files go to the temporary directory too, a failed run's as well
    with network.epanet_workdir(prefix="burstloc-eps-") as tmp, capture_diagnostics():
        sim = wntr.sim.EpanetSimulator(wn)
        results = sim.run_sim(file_prefix=os.path.join(tmp, "normal"))
    pressure = results.node["pressure"]
    solved = np.asarray(pressure.index, dtype=np.float64)
    heads = np.asarray(pressure[names].to_numpy(), dtype=np.float64)
    times = np.arange(0.0, hours * 3600.0, capture_interval)
    values = np.column_stack([np.interp(times, solved, heads[:, j]) for j in range(len(names))])
    _, noisy = SensorModel(noise_sigma=noise_sigma, seed=seed).apply(names, values, key="normal")
    return times, np.asarray(noisy, dtype=np.float64)
