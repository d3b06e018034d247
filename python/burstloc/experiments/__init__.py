"""Experiments on simulated bursts: calibration search, the paper's experiment, evaluation,
the robustness study, and their reports and plots. Built on every layer below; nothing in the
library imports it but :mod:`burstloc.cli`.

* :mod:`~burstloc.experiments.calibrate`: thresholds and localization settings from a baseline;
* :mod:`~burstloc.experiments.paper`: the paper's tables and scenario;
* :mod:`~burstloc.experiments.runs`: the runs of an evaluation (detector, interval, localizer);
* :mod:`~burstloc.experiments.harness`: the one harness both experiments score through
  (captured readings, the localizers' attempts, the tally), and
  :mod:`~burstloc.experiments.ranking`: the ranking localizers scored through the live monitor;
* :mod:`~burstloc.experiments.evaluate`: burst every pipe, replay, localize, score (every
  run's attempts: :mod:`~burstloc.experiments.scoring`);
* :mod:`~burstloc.experiments.event_set`, :mod:`~burstloc.experiments.specificity`: the
  non-burst events operated on a network, and bursts and those events together (how often a
  non-burst is reported as a burst; the classifier's calibration);
* :mod:`~burstloc.experiments.grid`, :mod:`~burstloc.experiments.study`: the
  one-factor-at-a-time robustness grid and its scoring;
* :mod:`~burstloc.experiments.report`, :mod:`~burstloc.experiments.plot`: tables, JSON, CSV,
  figures.
"""
