"""The live loop: readings in, burst decisions out. Never imports :mod:`burstloc.sim`, WNTR
or TSNet.

* :mod:`~burstloc.live.stream`: raw readings assembled into complete time steps;
* :mod:`~burstloc.live.monitor`: the detector bank, history and localizer over those steps,
  built from the stored configuration (no hydraulic model runs);
* :mod:`~burstloc.live.paper_locator`: the paper's real-time loop (windows, detector, rules).
"""
