"""Pressure changes that are not bursts, which a monitor must not call bursts.

:mod:`~burstloc.sim.events.operations` simulates valve and pump operations and demand steps
with the transient solver; :mod:`~burstloc.sim.events.normal` gives a day of normal operation
(the diurnal drift of every meter's pressure, from an extended-period EPANET run).
"""
