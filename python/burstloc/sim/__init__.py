"""The offline side: simulate bursts and sample them as meters would.

Nothing on the live path imports this package (it pulls in TSNet and WNTR).

* :mod:`~burstloc.sim.scenario`: burst scenarios and their results (NPZ files);
* :mod:`~burstloc.sim.tsnet`: the TSNet transient driver;
* :mod:`~burstloc.sim.time_step`: the time step TSNet will use, and the one to ask for;
* :mod:`~burstloc.sim.steady`: the steady-start check every simulation passes;
* :mod:`~burstloc.sim.tsnet_ready`: the network as TSNet needs it (closed pipes out, connector
  pipes where a pump or valve meets no single pipe);
* :mod:`~burstloc.sim.capture`: meter sampling (instantaneous or interval-averaged readings);
* :mod:`~burstloc.sim.sensors`: sensor noise models;
* :mod:`~burstloc.sim.cache`: the content-addressed cache of simulations on disk;
* :mod:`~burstloc.sim.signatures`: burst signatures from the hydraulic model (WNTR/EPANET steady
  states), cached on disk;
* :mod:`~burstloc.sim.prepare`: the localization model the ranking localizers are built from
  (pipe flow directions and lengths, path lengths to the meters, signatures), prepared offline
  for ``burstloc calibrate`` to store;
* :mod:`~burstloc.sim.placement`: meter placement (signature coverage or arrival-time
  separation) and the meter file;
* :mod:`~burstloc.sim.sweep`: many scenarios on local processes or a Dask cluster.
"""
