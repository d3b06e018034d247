"""Meter placement: which junctions should carry pressure meters, and the meter file.

:mod:`~burstloc.sim.placement.methods` is the front door (the ``coverage``, ``arrival`` and
``region`` methods, the meter file and a set's scores); :mod:`~burstloc.sim.placement.arrival`
separates the bursts' arrival-time patterns, :mod:`~burstloc.sim.placement.region` shortens
the search regions, :mod:`~burstloc.sim.placement.scaled` runs both on networks of
thousands of junctions, and :mod:`~burstloc.sim.placement.meter_file` reads and writes the
meter file. Placement reads the network model only (and, where pipes have their own wave
speed, :mod:`burstloc.wave_speeds`): no burst is simulated.
"""
