"""The transient solver: a burst's pressure waves through the network, TSNet's model.

:mod:`~burstloc.sim.transient.tsnet` is the burst driver (:func:`simulate_burst`,
:func:`simulate_many`) and :mod:`~burstloc.sim.transient.tsnet_run` one TSNet run (bursts and
operations alike); :mod:`~burstloc.sim.transient.tsnet_ready` makes the network what
TSNet can take (closed pipes out, connectors at pumps and valves) and
:mod:`~burstloc.sim.transient.tsnet_elements` its pumps and valves;
:mod:`~burstloc.sim.transient.intact` keeps per process what does not depend on the burst
pipe; :mod:`~burstloc.sim.transient.moc` (with :mod:`~burstloc.sim.transient.moc_layout`,
:mod:`~burstloc.sim.transient.moc_elements` and the Rust loop of
:mod:`~burstloc.sim.transient.moc_rust`) solves TSNet's equations vectorized;
:mod:`~burstloc.sim.transient.time_step` gives the step TSNet will use, and
:mod:`~burstloc.sim.transient.steady` the steady-start check every run passes. The private
``_tsnet_*`` modules patch and speed up TSNet 0.3.1 on current stacks.
"""
