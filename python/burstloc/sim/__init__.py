"""The offline side: simulate bursts and other transients, and prepare what the live path uses.

Nothing on the live path imports this package (it pulls in TSNet and WNTR). Its rooms, each a
sub-package with one job, import one another only in this order (``tests/test_layers.py``):

* :mod:`~burstloc.sim.scenarios`: what to simulate and what comes out (burst scenarios and
  their results, meter sampling, sensor noise, monitor feeds), the content-addressed cache on
  disk and the sweep of many scenarios over processes or a Dask cluster;
* :mod:`~burstloc.sim.transient`: the transient solver (TSNet's model, burstloc's vectorized
  MOC with its Rust time loop, the time step, the steady-start check);
* :mod:`~burstloc.sim.events`: transients that are not bursts (valve and pump operations,
  demand steps) and a day of normal operation;
* :mod:`~burstloc.sim.signatures`: burst signatures from steady states (exact, hybrid,
  linearized);
* :mod:`~burstloc.sim.model`: the localization model ``burstloc calibrate`` stores (flow
  directions, arrival geometry, signatures);
* :mod:`~burstloc.sim.placement`: meter placement (coverage, arrival, region; scaled for
  large networks) and the meter file.
"""
