"""The paper's experiment as data: its configurations (Tables I, II), its published results
(Tables III, IV, V) and the scenario choices it leaves open, as named configurations.

Source: Mzembegwa & Nyirenda, "Real-time Pipe Burst Localization in Water Distribution
Networks Using Change Point Detection Algorithms", section V. Pipe names and node names are
the paper's (``networks/paper15.inp`` uses the same). A prediction ``"R1 - N3"`` is the pipe
from ``R1`` to ``N3`` in steady-state flow direction.

Everything here is plain data: no simulator import.
"""

from __future__ import annotations

from dataclasses import dataclass

from burstloc.constants import CAPTURE_INTERVALS, WAVE_SPEED

__all__ = [
    "DEFAULT_MODE",
    "PAPER_PIPES",
    "PAPER_RUNS",
    "PRINTED_TOTALS",
    "SCENARIO",
    "TABLE_I",
    "TABLE_II",
    "TABLE_III",
    "TABLE_IV",
    "TABLE_V",
    "TABLE_V_AVERAGE",
    "TRUE_PIPES",
    "TSNET_EXAMPLE_SCENARIO",
    "PaperRun",
    "ScenarioConfig",
    "published_correct",
    "published_prediction",
]


@dataclass(frozen=True)
class PaperRun:
    """One row of Table I (CUSUM) or II (Shewhart): a scenario of the paper."""

    scenario: str
    detector: str
    capture_interval: float
    threshold: float
    localization_interval: int


#: Table I, "Parameters used for the CUSUM approach" (threshold in m). The paper gives no
#: drift; TSNet's detect_cusum has no default, we use 0 (see docs/method.md).
TABLE_I: tuple[PaperRun, ...] = (
    PaperRun("S_C1", "cusum", 0.2, 0.3, 5),
    PaperRun("S_C2", "cusum", 2.0, 2.0, 10),
    PaperRun("S_C3", "cusum", 5.0, 10.0, 10),
    PaperRun("S_C4", "cusum", 10.0, 13.0, 10),
)

#: Table II, "Parameters used for the Shewhart approach". Algorithm 2 uses this single
#: threshold both as the multiplier ``s`` of eq. 3 and as the absolute limit (m).
TABLE_II: tuple[PaperRun, ...] = (
    PaperRun("S_S1", "shewhart", 0.2, 1.5, 5),
    PaperRun("S_S2", "shewhart", 2.0, 3.0, 10),
    PaperRun("S_S3", "shewhart", 5.0, 2.0, 10),
    PaperRun("S_S4", "shewhart", 10.0, 3.0, 10),
)

#: Both tables: the ``burstloc evaluate --localizer paper`` experiment.
PAPER_RUNS: tuple[PaperRun, ...] = TABLE_I + TABLE_II

#: The capture intervals of the paper (s), in table column order.

#: The 25 pipes in the order of Tables III and IV (there is no pipe 10).
PAPER_PIPES: tuple[str, ...] = (
    "P1", "P2", "P3", "P4", "P5", "P6", "P7", "P8", "P9",
    "1", "2", "3", "4", "5", "6", "7", "8", "9", "11", "12", "13", "14", "15", "16", "17",
)  # fmt: skip

#: Each pipe's true ends in flow direction, as the tables' bold (correct) entries give them.
TRUE_PIPES: dict[str, str] = {
    "P1": "R1 - N3", "P2": "N3 - N4", "P3": "N3 - N2", "P4": "N4 - N6", "P5": "N4 - N2",
    "P6": "N2 - N5", "P7": "N5 - N7", "P8": "N6 - N5", "P9": "N2 - N6", "1": "N7 - 4",
    "2": "5 - 8", "3": "1 - 2", "4": "N3 - 1", "5": "2 - 3", "6": "3 - 4", "7": "4 - 5",
    "8": "N2 - 2", "9": "N5 - 3", "11": "6 - 7", "12": "N6 - 6", "13": "7 - N8",
    "14": "N8 - 8", "15": "N7 - 7", "16": "N7 - N8", "17": "1 - N2",
}  # fmt: skip

#: Table III, "Burst link localization results using CUSUM": pipe -> predictions for
#: S_C1..S_C4 (capture intervals 0.2, 2, 5, 10 s).
TABLE_III: dict[str, tuple[str, str, str, str]] = {
    "P1": ("R1 - N3", "N7 - 7", "7 - N8", "R1 - N3"),
    "P2": ("N3 - N4", "N3 - N4", "N3 - N4", "N3 - N4"),
    "P3": ("N3 - N2", "N8 - 8", "N2 - 2", "N4 - N2"),
    "P4": ("N4 - N6", "4 - 5", "N4 - N6", "N4 - N6"),
    "P5": ("N4 - N2", "N7 - N8", "N3 - N4", "N3 - N4"),
    "P6": ("N2 - N5", "N5 - N7", "N6 - N5", "N6 - N5"),
    "P7": ("N6 - N5", "N5 - N7", "N8 - 8", "N5 - N7"),
    "P8": ("N6 - N5", "N7 - N8", "N2 - N6", "N2 - N6"),
    "P9": ("N2 - N6", "N6 - 6", "N2 - N6", "N2 - N6"),
    "1": ("N7 - 4", "N7 - 4", "4 - 5", "5 - 8"),
    "2": ("5 - 8", "5 - 8", "4 - 5", "4 - 5"),
    "3": ("1 - 2", "1 - 2", "1 - 2", "1 - 2"),
    "4": ("N3 - 1", "N3 - 1", "N3 - 1", "N3 - 1"),
    "5": ("2 - 3", "2 - 3", "2 - 3", "2 - 3"),
    "6": ("3 - 4", "3 - 4", "4 - 5", "4 - 5"),
    "7": ("3 - 4", "4 - 5", "4 - 5", "4 - 5"),
    "8": ("N2 - 2", "N2 - 2", "N2 - 2", "N2 - 2"),
    "9": ("N5 - 3", "N5 - 3", "N5 - 3", "2 - 3"),
    "11": ("6 - 7", "6 - 7", "6 - 7", "6 - 7"),
    "12": ("N6 - 6", "N6 - 6", "N6 - 6", "N6 - 6"),
    "13": ("7 - N8", "7 - N8", "7 - N8", "7 - N8"),
    "14": ("N8 - 8", "N8 - 8", "5 - 8", "5 - 8"),
    "15": ("N7 - 7", "N7 - 7", "N7 - 7", "N7 - 7"),
    "16": ("N7 - N8", "N7 - N8", "7 - N8", "7 - N8"),
    "17": ("N3 - 1", "1 - N2", "N3 - 1", "N3 - 1"),
}

#: Table IV, "Burst link localization results using Shewhart" (S_S1..S_S4).
TABLE_IV: dict[str, tuple[str, str, str, str]] = {
    "P1": ("R1 - N3", "4 - 5", "N5 - 3", "N3 - N4"),
    "P2": ("N3 - N4", "N3 - N4", "N8 - 8", "N3 - N4"),
    "P3": ("N3 - N2", "5 - 8", "N2 - 2", "N4 - N2"),
    "P4": ("N3 - N4", "4 - 5", "N6 - 6", "N6 - N5"),
    "P5": ("N4 - N2", "4 - 5", "N8 - 8", "N3 - N4"),
    "P6": ("N2 - N5", "5 - 8", "N5 - N7", "N6 - N5"),
    "P7": ("N5 - N7", "N5 - N7", "N8 - 8", "N5 - N7"),
    "P8": ("N6 - N5", "N8 - 8", "N6 - 6", "N2 - N6"),
    "P9": ("N2 - N6", "N6 - 6", "N5 - N7", "N2 - N6"),
    "1": ("N7 - 4", "N7 - 4", "4 - 5", "3 - 4"),
    "2": ("5 - 8", "5 - 8", "4 - 5", "4 - 5"),
    "3": ("1 - 2", "1 - 2", "1 - 2", "1 - 2"),
    "4": ("N3 - 1", "N3 - 1", "2 - 3", "N3 - 1"),
    "5": ("2 - 3", "2 - 3", "2 - 3", "2 - 3"),
    "6": ("3 - 4", "3 - 4", "4 - 5", "3 - 4"),
    "7": ("4 - 5", "4 - 5", "4 - 5", "4 - 5"),
    "8": ("N2 - 2", "N2 - 2", "N2 - 2", "N2 - 2"),
    "9": ("N5 - 3", "N5 - 3", "N5 - 3", "2 - 3"),
    "11": ("6 - 7", "6 - 7", "6 - 7", "6 - 7"),
    "12": ("N6 - 6", "N6 - 6", "7 - N8", "N6 - 6"),
    "13": ("7 - N8", "7 - N8", "7 - N8", "7 - N8"),
    "14": ("N8 - 8", "N8 - 8", "5 - 8", "5 - 8"),
    "15": ("N7 - 7", "N7 - 7", "N7 - 7", "N7 - 7"),
    "16": ("N7 - N8", "N7 - N8", "7 - N8", "N7 - N8"),
    "17": ("1 - N2", "1 - N2", "N3 - 1", "N3 - 1"),
}

#: The "Correct:" rows printed under Tables III and IV, which disagree with the tables'
#: own entries (see :func:`published_correct`: 22/18/13/14 and 24/18/8/14).
PRINTED_TOTALS: dict[str, tuple[int, int, int, int]] = {
    "cusum": (23, 18, 13, 16),
    "shewhart": (24, 18, 8, 15),
}

#: Table V, "Comparison of CUSUM and Shewhart's accuracy" (%), per capture interval; it
#: matches the printed totals (23/25 = 92%), not the tables' entries.
TABLE_V: dict[str, tuple[float, float, float, float]] = {
    "cusum": (92.0, 72.0, 52.0, 64.0),
    "shewhart": (96.0, 72.0, 32.0, 60.0),
}

#: Table V's "Average" row (%).
TABLE_V_AVERAGE: dict[str, float] = {"cusum": 70.0, "shewhart": 65.0}

_TABLES = {"cusum": TABLE_III, "shewhart": TABLE_IV}


def published_prediction(detector: str, pipe: str, capture_interval: float) -> str:
    """The paper's prediction (``"start - end"``) for a burst on ``pipe``."""
    column = CAPTURE_INTERVALS.index(float(capture_interval))
    return _TABLES[detector][pipe][column]


def published_correct(detector: str) -> tuple[int, ...]:
    """Correct predictions per capture interval, counted from the table entries themselves."""
    table = _TABLES[detector]
    return tuple(
        sum(table[p][k] == TRUE_PIPES[p] for p in PAPER_PIPES)
        for k in range(len(CAPTURE_INTERVALS))
    )


@dataclass(frozen=True)
class ScenarioConfig:
    """How every burst is simulated where the paper is silent (see docs/method.md).

    ``burst_start`` (s), ``opening_time`` (s), ``burst_coeff`` (TSNet's final emitter
    coefficient, m³/s/m^½), ``position`` (fraction of the pipe from its INP start node),
    ``wave_speed`` (m/s, TSNet's default as in the paper) and ``duration`` (s). ``duration=None``
    lets the evaluation choose the shortest simulation that gives every run ``2 x interval``
    readings after the burst whatever the phase: onset + (2 x interval + 1) x capture interval,
    rounded up to a second (220 s for the paper's experiment with :data:`SCENARIO`: 10 s
    onset + 21 x 10 s); an explicit duration too short for a run is an error.
    ``min_pipe_length`` (m, ``None`` = the network as it is) simulates the transient-ready
    model (``BurstScenario.min_pipe_length``, :mod:`burstloc.skeleton`). ``solver``: the
    transient solver (``BurstScenario.solver``: ``"vectorized"`` or ``"tsnet"``).
    """

    burst_start: float = 10.0
    opening_time: float = 1.0
    burst_coeff: float = 0.01
    position: float = 0.5
    wave_speed: float = WAVE_SPEED
    duration: float | None = None
    min_pipe_length: float | None = None
    solver: str = "vectorized"

    def parameters(self) -> dict[str, float | str | None]:
        """The scenario fields as keyword arguments of
        ``burstloc.sim.scenarios.scenario.BurstScenario``
        (``min_pipe_length`` only when set)."""
        extra = {} if self.min_pipe_length is None else {"min_pipe_length": self.min_pipe_length}
        return {
            "burst_start": self.burst_start,
            "opening_time": self.opening_time,
            "burst_coeff": self.burst_coeff,
            "position": self.position,
            "wave_speed": self.wave_speed,
            "duration": self.duration,
            "solver": self.solver,
            **extra,
        }


#: TSNet's documented burst example (``ts = 1, tc = 1, final_burst_coeff = 0.01``, onset moved
#: to 10 s): the simulation helper's defaults, kept for comparison (docs/method.md, table S).
TSNET_EXAMPLE_SCENARIO = ScenarioConfig(burst_start=10.0, opening_time=1.0, burst_coeff=0.01)

#: The scenario of the default experiment (docs/method.md, "Choosing the scenario"): a burst
#: that opens in 0.3 s to a final emitter coefficient of 0.02 m³/s/m^½ (about 280 L/s at the
#: network's 190 m of head), at the middle of the pipe, starting at 10 s (TSNet's example onset).
#: The onset is deliberately NOT tuned: where the reading windows fall relative to the burst
#: decides most of the 0.2 s accuracy of the paper's rules (an onset of 10.12 s would lift the
#: 5-phase figures from 80% to 96-97%), and a real burst does not choose its moment.
SCENARIO = ScenarioConfig(burst_start=10.0, opening_time=0.3, burst_coeff=0.02)

#: The detection mode of the default experiment ("window": the paper's per-window call).
DEFAULT_MODE = "window"
