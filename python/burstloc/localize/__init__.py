"""From detector alarms to a burst pipe: evidence, localizers, the decision rule.

On the live path: nothing here runs a hydraulic model or imports the simulator.

* :mod:`~burstloc.localize.evidence`: what a localizer reads (:class:`BurstEvidence`) and
  answers (:class:`Ranking`);
* :mod:`~burstloc.localize.paper_rules` and :mod:`~burstloc.localize.detection`: the paper's
  rules over windows of readings;
* :mod:`~burstloc.localize.arrival`, :mod:`~burstloc.localize.signature`,
  :mod:`~burstloc.localize.fused`: the ranking localizers;
* :mod:`~burstloc.localize.steady_level`: the estimators of a meter's new steady level;
* :mod:`~burstloc.localize.decide`: when a ranking localizer answers, and what.
"""
