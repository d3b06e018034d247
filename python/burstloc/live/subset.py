"""The ranking localizers restricted to the meters that report.

When meters go silent the monitor localizes with the others only: the arrival model (path
lengths from the pipes' end nodes) and the burst signatures are restricted to the reporting
meters, from the public data of the stored
:class:`~burstloc.localize.model.LocalizationModel` (no hydraulic model runs).
:class:`SubsetLocalizers` builds each subset once and keeps the few it has built.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Collection, Mapping, Sequence
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import ConfigError
from burstloc.localize.decide import RankingLocalizers
from burstloc.localize.evidence import IndexedAlarm, Localizer
from burstloc.localize.model import LocalizationModel

__all__ = ["SubsetLocalizers", "restricted_model", "taking_part"]


def restricted_model(model: LocalizationModel, meters: Sequence[str]) -> LocalizationModel:
    """``model`` for ``meters`` only (a subset of its meters, in its order).

    Raises:
        ConfigError: no meter, or a meter the model does not have.
    """
    unknown = [m for m in meters if m not in model.meters]
    if unknown or not meters:
        raise ConfigError(f"cannot restrict the localization model to meters {list(meters)}")
    cols = [model.meters.index(m) for m in meters]
    return replace(  # the rest as it is: wave speed, tolerances, timing factor, connectors
        model,
        meters=tuple(meters),
        node_distances={node: row[cols] for node, row in model.node_distances.items()},
        signature_sets=tuple(s.for_meters(meters) for s in model.signature_sets),
        clock_offsets=(
            None
            if model.clock_offsets is None
            else {m: model.clock_offsets[m] for m in meters if m in model.clock_offsets}
        ),
        fronts=None if model.fronts is None else {p: r[cols] for p, r in model.fronts.items()},
    )


class SubsetLocalizers:
    """Ranking localizers for subsets of a model's meters, built on demand (at most ``keep``
    subsets kept, least recently used dropped)."""

    def __init__(self, model: LocalizationModel, keep: int = 8) -> None:
        self.model = model
        self.keep = keep
        self._built: OrderedDict[tuple[str, ...], RankingLocalizers] = OrderedDict()

    def get(self, meters: Sequence[str]) -> RankingLocalizers:
        """The localizers of ``meters`` (ordered like the model's meters)."""
        key = tuple(m for m in self.model.meters if m in set(meters))
        found = self._built.get(key)
        if found is None:
            found = RankingLocalizers.from_model(restricted_model(self.model, key))
            self._built[key] = found
            while len(self._built) > self.keep:
                self._built.popitem(last=False)
        self._built.move_to_end(key)
        return found


def taking_part(
    meters: Sequence[str],
    excluded: Collection[str],
    localizers: Mapping[str, Localizer],
    subsets: SubsetLocalizers | None,
    readings: NDArray[np.float64],
    alarms: Sequence[IndexedAlarm],
) -> tuple[NDArray[np.float64], list[IndexedAlarm], tuple[str, ...], Mapping[str, Localizer]]:
    """``(readings, alarms, meters, localizers)`` of the meters taking part: all of ``meters``
    but the ``excluded``, with the subset's own localizers (from ``subsets``; without them, the
    ``localizers`` as they are and every meter). ``readings`` has a column per meter and the
    alarms' channels index ``meters``; both are returned for the meters taking part."""
    part = [j for j, m in enumerate(meters) if m not in excluded]
    if subsets is None or len(part) == len(meters):
        return readings, list(alarms), tuple(meters), localizers
    column = {j: k for k, j in enumerate(part)}
    kept = tuple(meters[j] for j in part)
    moved = [
        IndexedAlarm(column[a.channel], a.index, a.start, a.amplitude)
        for a in alarms
        if a.channel in column
    ]
    return readings[:, part], moved, kept, subsets.get(kept)
