"""The constants every layer shares: one home for each (imported by all, importing nothing).

* :data:`CAPTURE_INTERVALS`: the meters' reporting periods the paper evaluates (s).
* :data:`WAVE_SPEED`: the pressure-wave speed TSNet and the paper use (m/s).
* :data:`SCENARIO_DURATION`: how long a burst scenario is simulated (s).
* :data:`BURST_SHARE`, :data:`BURST_FLOW`: the size of the commands' default burst (a share of
  the network's demand, at most a flow in m³/s).
* :data:`DETECTORS`, :data:`RANKING_LOCALIZERS`, :data:`LOCALIZERS`: names accepted everywhere.
* :data:`METER_MODELS` / :data:`MeterModel`: what a meter's reading is.
* :data:`CANDIDATE_POSITIONS`: burst positions along a pipe that the localizers try.
* :data:`SIGNATURE_DECISION_DELAY`: when the steady-state signature is read after a burst (s).
* :data:`MAX_SAMPLE`: the largest reading magnitude the detectors take (``cpd_core::MAX_SAMPLE``).
* :data:`PRESSURE_NOISE`: how far below zero a steady-state pressure is numerical noise (m).
* :data:`VACUUM_HEAD`: the pressure head of absolute vacuum (m), below which no water is.
"""

from __future__ import annotations

from typing import Literal

__all__ = [
    "BURST_FLOW",
    "BURST_SHARE",
    "CANDIDATE_POSITIONS",
    "CAPTURE_INTERVALS",
    "CLOCK_TOLERANCE",
    "DETECTORS",
    "EXACT_SIGNATURES_UP_TO",
    "HYBRID_SIGNATURES_UP_TO",
    "LOCALIZERS",
    "MAX_SAMPLE",
    "MAX_TIMING_FACTOR",
    "METER_MODELS",
    "PRESSURE_NOISE",
    "RANKING_LOCALIZERS",
    "SCENARIO_DURATION",
    "SIGNATURE_DECISION_DELAY",
    "VACUUM_HEAD",
    "WAVE_SPEED",
    "WAVE_SPEED_TOLERANCE",
    "Detector",
    "MeterModel",
]

CAPTURE_INTERVALS: tuple[float, ...] = (0.2, 2.0, 5.0, 10.0)

#: The detectors refuse a sample beyond +-this (InputError, like a NaN): no meter reads 1e100 of
#: anything, and below it a window's sum of squares cannot overflow. The Rust core's
#: ``MAX_SAMPLE``; ``tests/test_detectors.py`` checks the two agree.
MAX_SAMPLE = 1e100
"""Capture intervals (s) of the paper's experiment, and the defaults of every command."""

BURST_SHARE = 0.05
"""The default burst of ``burstloc simulate`` and ``evaluate`` draws this share of the network's
demand (at the steady state it opens from), at most :data:`BURST_FLOW`: 2.0 L/s on L-TOWN
(40.8 L/s of demand), 2.75 L/s on awumah11, 5 L/s on paper15 and the larger networks. A burst a
utility sees and a network feeds: what a network carries is sized by its demand, so a share of
it is a burst its mains can feed, where one flow for every network is a leak on a city's
network and more than a district's pipes can take. Opened in 0.3 s it leaves every junction
above zero pressure through the transient on every pipe of every committed network, EPANET's
Net1, Net2 and Anytown and L-TOWN (8.6 m or more on its 905 pipes), and takes none of Net3's
below where it was (one is at -0.5 m before any burst) (``benches/bench_burst_size.py``), where
5 L/s takes one L-TOWN junction to -0.8 m and 10 L/s dips below zero on 4 of 30 pipes; the paper's
coefficient (0.02 m³/s/m^½: 127-276 L/s, up to 5 times a network's demand) takes junctions
below zero on awumah11, Net2 and every L-TOWN burst. The paper's experiment
(``--localizer paper``) keeps the paper's coefficient."""

BURST_FLOW = 0.005
"""The largest default burst (m³/s): 5 L/s, the flow its emitter draws at the burst point's
pressure before it opens (:data:`BURST_SHARE`)."""


WAVE_SPEED = 1200.0
"""Pressure-wave speed (m/s): TSNet's default, the paper's setting."""

WAVE_SPEED_TOLERANCE = 0.05
"""Relative uncertainty of the wave's travel time along a path (one standard deviation): the
wave speed of real mains is known to a few per cent (material, wall thickness, air), and a
model's pipe lengths and the transient model's short pipes (lengthened to a minimum) add
their own. The search regions widen with the path: ``tolerance x path / wave speed``."""

CLOCK_TOLERANCE = 0.0
"""Uncertainty (s, one standard deviation) of each meter's clock: GPS-disciplined loggers are
within a millisecond, NTP-synchronised ones a few milliseconds (``burstloc calibrate
--clock-tolerance``)."""

MAX_TIMING_FACTOR = 10.0
"""Most the search regions' timing error is widened by at one capture interval, over the stated
one (:mod:`burstloc.experiments.region_spread` fits it on simulated bursts): beyond it the
arrivals say little, and a fit that asks for more says the model is wrong."""

SCENARIO_DURATION = 220.0
"""Simulated seconds of a burst scenario: the burst at 10 s plus the signature's decision delay
(150 s) and the settling readings after it."""

Detector = Literal["cusum", "shewhart"]
"""A change-point detector: the two-sided CUSUM or the Shewhart chart."""

DETECTORS: tuple[Detector, ...] = ("cusum", "shewhart")

MeterModel = Literal["instantaneous", "interval-averaged"]
"""How a meter turns pressure into a reading: an instantaneous sample at the reading's time stamp
(the paper's model), or the mean over the capture interval that ends at the time stamp (what most
loggers report)."""

METER_MODELS: tuple[MeterModel, ...] = ("instantaneous", "interval-averaged")

RANKING_LOCALIZERS: tuple[str, ...] = ("arrival", "signature", "fused")
"""The localizers that rank every pipe (behind :class:`burstloc.localize.Localizer`)."""

LOCALIZERS: tuple[str, ...] = ("paper", *RANKING_LOCALIZERS)
"""Every localizer: the paper's rules, then the ranking localizers."""

CANDIDATE_POSITIONS: tuple[float, ...] = tuple(round(0.1 * i, 1) for i in range(1, 10))
"""Candidate burst positions along each pipe (fractions of its length from its INP start node)
that the arrival and signature localizers try; a pipe keeps its best-fitting position."""

SEARCHABLE = 1000.0
"""Longest search region (m of main) a crew is sent to search: what the evaluation's and the
placement scores' "searchable" shares count."""

SIGNATURE_DECISION_DELAY = 150.0
"""Seconds after a burst's onset at which the signature localizer reads the lasting drop."""

EXACT_SIGNATURES_UP_TO = 3000
"""Pipes up to which ``calibrate`` computes the burst signatures exactly by default (one EPANET
steady state per pipe and position): seconds to a minute per position (L-TOWN, 905 pipes: about
4 s). Above it the cost grows with the square of the network (BWSN2, 14 822 pipes: about 8 CPU
minutes per position, nine positions) and the default is the hybrid method (one exact mid-pipe
drop per pipe, the positions along it from the linearized steady state:
:func:`burstloc.sim.signatures.compute.linear_signature_sets`)."""

HYBRID_SIGNATURES_UP_TO = 20000
"""Pipes up to which the default is the hybrid method; above it the linearized steady state alone
(seconds on any network; a large burst's shape approximated)."""

VACUUM_HEAD = -10.33
"""The pressure head (m of water, gauge) of absolute vacuum at sea level: 101.325 kPa / (rho g).
No water is below it; a steady state that puts a junction there is a fault of the model."""

PRESSURE_NOISE = 1e-3
"""How far (m) below atmospheric a junction's steady-state pressure may be and still count as
zero: EPANET's solver leaves pressures of the order of its accuracy around a true zero (hanoi's
junctions at -1.9e-5 m, all its demands undelivered). Below this a junction with a demand starts
at a negative pressure, which the transient model cannot (TSNet's demand law ``q = k sqrt(p)``);
within it the junction is taken at zero pressure."""
