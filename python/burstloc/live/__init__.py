"""The live loop: readings in, burst decisions out. Never imports :mod:`burstloc.sim`.

* :mod:`~burstloc.live.stream`: raw readings assembled into complete time steps;
* :mod:`~burstloc.live.monitor`: the detector bank, history and localizer over those steps.
"""
