"""Scenarios and sweeps: what is simulated, what comes out, and how many runs are shared.

:mod:`~burstloc.sim.scenarios.scenario` names a burst (pipe, position, size, timing),
:mod:`~burstloc.sim.scenarios.result` holds its result (every junction's head over time, or
the recorded ones', NPZ files); :mod:`~burstloc.sim.scenarios.capture`
samples a result as meters would (instantaneous or interval-averaged readings, any clock
phase); :mod:`~burstloc.sim.scenarios.sensors` adds the meters' noise;
:mod:`~burstloc.sim.scenarios.feed` writes the readings as the monitor's CSV feed;
:mod:`~burstloc.sim.scenarios.cache` is the content-addressed cache of arrays on disk, and
:mod:`~burstloc.sim.scenarios.sweep` runs many scenarios on local processes or a Dask
cluster. Nothing here solves a transient: the solver is :mod:`burstloc.sim.transient`.
"""
