"""From detector alarms to a burst pipe: evidence, localizers, the decision rule.

On the live path: nothing here runs a hydraulic model or imports the simulator.

* :mod:`~burstloc.localize.evidence`: what a localizer reads (:class:`BurstEvidence`) and
  answers (:class:`Ranking`), the :class:`Localizer` protocol, a detector's :class:`Change`;
* :mod:`~burstloc.localize.paper_rules` and :mod:`~burstloc.localize.detection`: the paper's
  rules over windows of readings;
* :mod:`~burstloc.localize.arrival`, :mod:`~burstloc.localize.signature`,
  :mod:`~burstloc.localize.fused`: the ranking localizers; :mod:`~burstloc.localize.pipes`:
  the candidate pipes and the points they name;
* :mod:`~burstloc.localize.steady_level`: the estimators of a meter's new steady level;
* :mod:`~burstloc.localize.model`: the stored localization model (what the ranking localizers
  need of the network, computed offline by :mod:`burstloc.sim.model.prepare`);
* :mod:`~burstloc.localize.config`: the stored configuration (calibrated detector settings and
  the model) that ``burstloc calibrate`` writes and the monitor reads, one
  :class:`~burstloc.localize.interval.IntervalCalibration` per capture interval
  (:mod:`~burstloc.localize.interval`: thresholds, delays, the speed fronts are heard at);
* :mod:`~burstloc.localize.decide`: the localizers built from a model, when a ranking localizer
  answers, and what (a :class:`~burstloc.localize.decide.Decision`);
* :mod:`~burstloc.localize.corroborate`: how many meters make a burst, and until when.

The results, one lineage: a ranking localizer answers a
:class:`~burstloc.localize.evidence.Ranking`; a
:class:`~burstloc.localize.decide.Decision` is that ranking at a reading time (with the first
alarm and whether the fused localizer waited), what the monitor reports and the experiments
score; the paper's rules answer a :class:`~burstloc.localize.paper_rules.Localization` (one
pipe and the rule that named it). An experiment's
:class:`~burstloc.experiments.harness.Attempt` holds one or the other.
"""
