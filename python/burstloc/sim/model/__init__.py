"""The localization model, prepared offline for ``burstloc calibrate`` to store.

:mod:`~burstloc.sim.model.prepare` solves the network's steady state once for the flow
directions, measures the path lengths from every pipe to the meters (the arrival geometry the
arrival localizer and the search regions use) and takes the burst signatures from
:mod:`burstloc.sim.signatures`. The live path reads the stored model and never this package.
"""
