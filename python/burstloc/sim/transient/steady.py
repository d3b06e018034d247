"""The steady-start check: a transient run is an experiment only if nothing moves before its event.

TSNet starts its transient from EPANET's steady state. Where TSNet's boundary conditions do not
reproduce that state (a pump, a valve or a tank TSNet models differently from EPANET, a short
pipe), the heads swing before anything happens, and a burst "found" in that swing is noise.
After every simulation, :func:`check_steady_start` compares each meter's pressure head over the
part of the run before the event's onset with its initial head; a movement above
:data:`STEADY_TOLERANCE` raises :class:`~burstloc.exceptions.UnsteadyStartError` naming the
junction, the movement and the network, instead of returning the run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from burstloc._validate import attributes
from burstloc.exceptions import UnsteadyStartError

__all__ = ["STEADY_TOLERANCE", "SteadyStart", "check_steady_start", "steady_start"]

#: The largest movement (m) of any meter's pressure head before the onset that still counts as a
#: steady start: 5 cm, about 50 times what the steady networks move (paper15 and
#: paper15_assets: 0.1-0.5 mm over 30 s), 10 times below the smallest noise level of the study
#: (sigma 0.05 m is the noise it adds; a burst moves heads by metres).
STEADY_TOLERANCE = 0.05


@dataclass(frozen=True)
class SteadyStart:
    """The largest movement before the onset: ``movement`` (m, absolute) of ``junction``'s
    pressure head from its initial value, at ``time`` (s; ``None`` when no step precedes the
    onset); ``onset`` (s) is the end of the window."""

    junction: str | None
    movement: float
    time: float | None
    onset: float

    def as_metadata(self) -> dict[str, object]:
        """The record stored in a simulation's metadata (``steady_start``)."""
        return {
            "max_movement_m": self.movement,
            **attributes(self, "junction", "time", "onset"),
            "tolerance_m": STEADY_TOLERANCE,
        }


def steady_start(
    times: np.ndarray, heads: np.ndarray, meters: Sequence[str], onset: float
) -> SteadyStart:
    """Measure the largest movement of any meter's head (``heads``, ``(T, M)``) from its value at
    the first step, over the steps strictly before ``onset`` (s)."""
    before = np.asarray(times) < onset
    if before.sum() < 2:
        return SteadyStart(None, 0.0, None, float(onset))
    window = np.abs(heads[before] - heads[0])
    step, meter = np.unravel_index(int(np.argmax(window)), window.shape)
    return SteadyStart(
        str(meters[int(meter)]), float(window[step, meter]), float(times[step]), float(onset)
    )


def check_steady_start(
    times: np.ndarray,
    heads: np.ndarray,
    meters: Sequence[str],
    onset: float,
    network: str,
) -> SteadyStart:
    """:func:`steady_start`, refused above :data:`STEADY_TOLERANCE`.

    Raises:
        UnsteadyStartError: a meter's head moved more than the tolerance before ``onset``; the
            message names the junction, the movement in metres, when, and ``network``.
    """
    found = steady_start(times, heads, meters, onset)
    if found.movement > STEADY_TOLERANCE:
        raise UnsteadyStartError(
            network,
            str(found.junction),
            found.movement,
            float(found.time or 0.0),
            onset,
            STEADY_TOLERANCE,
        )
    return found
