"""Burst signatures: each meter's lasting pressure drop for a burst at each point of each pipe.

:mod:`~burstloc.sim.signatures.compute` is the front door (the exact, hybrid and linearized
methods, cached on disk); exact signatures solve one EPANET steady state per pipe and position
in one EPANET project split in place (:mod:`~burstloc.sim.signatures.epanet_inplace`), the
linearized ones factorize the steady state once (:mod:`~burstloc.sim.signatures.linear`).
"""
