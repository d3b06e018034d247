"""What the meters hear of a perturbed truth in ``burstloc evaluate``.

The simulation of a perturbed truth (per-pipe wave speeds and roughness) is made by the
simulator (:class:`burstloc.sim.scenarios.scenario.BurstScenario`'s ``truth``); what remains is
how the meters read it (:class:`Hearing`): each meter's clock off by its own draw
(:func:`burstloc.sim.scenarios.perturb.shift_clocks`), and the metered junction nearest the
burst (network distance from the burst point, :class:`burstloc.experiments.position.
NetworkDistance`) silent from ``silent_meter`` seconds after the burst starts
(:func:`burstloc.sim.scenarios.perturb.silence`: NaN, which the harness passes to the monitor
as the live feed does, a meter named in :attr:`burstloc.readings.Step.filled`). The meters'
capture (clock phase, meter model, noise) then runs as for any burst.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

from burstloc.exceptions import ConfigError
from burstloc.experiments.position import NetworkDistance, true_point
from burstloc.sim.scenarios.perturb import TruthPerturbation, clock_offsets, shift_clocks, silence

if TYPE_CHECKING:
    from wntr.network import WaterNetworkModel

    from burstloc.sim.scenarios.result import ScenarioResult

__all__ = ["Hearing", "check_truth"]


def check_truth(truth: TruthPerturbation | None, localizers: Sequence[str]) -> None:
    """Refuse a silent meter for the paper's rules (they read every junction and have no
    policy for a missing reading).

    Raises:
        ConfigError: naming the option.
    """
    if truth is not None and truth.silent_meter is not None and "paper" in localizers:
        raise ConfigError(
            "--truth-silent-meter needs a ranking localizer: the paper's rules read every "
            "junction and have no policy for a missing reading"
        )


@dataclass
class Hearing:
    """How the meters read each burst of an evaluation under ``truth``.

    Attributes:
        truth: the perturbation (only its clock offset and silent meter act here).
        wn: the model (the burst points and network distances).
        metered: the junctions that carry meters (the silent one is the nearest of them);
            ``None``: every junction of each result.
        silent: the silent meter of each burst pipe read so far.
    """

    truth: TruthPerturbation
    wn: WaterNetworkModel
    metered: Sequence[str] | None = None
    silent: dict[str, str] = field(default_factory=dict)
    _distance: NetworkDistance | None = field(default=None, init=False, repr=False)

    def __call__(self, result: ScenarioResult) -> ScenarioResult:
        """``result`` as the meters hear it (itself when the truth is read exactly)."""
        if not self.truth.heard:
            return result
        heads = shift_clocks(result.time, result.heads, clock_offsets(self.truth, result.junctions))
        if self.truth.silent_meter is not None:
            meter = self.nearest_meter(result)
            self.silent[result.pipe] = meter
            after = float(result.metadata["burst_start"]) + self.truth.silent_meter
            heads = silence(result.time, heads, list(result.junctions).index(meter), after)
        return replace(result, heads=heads)

    def nearest_meter(self, result: ScenarioResult) -> str:
        """The metered junction nearest (network distance) to ``result``'s burst point."""
        if self._distance is None:
            self._distance = NetworkDistance(self.wn)
        distance, point = self._distance, true_point(result, self.wn)
        metered = list(result.junctions) if self.metered is None else list(self.metered)
        return min(metered, key=lambda m: (distance.to_node(point, m), m))
