"""Is it a burst? Every alarm classified as ``burst``, ``other`` (an event) or ``unsure``.

Valves are operated, pumps trip and start, large consumers switch on: each sends a transient
through the network, and a monitor that names a "burst pipe" for each is useless in a control
room. At the signature's decision time (onset + ``decision_delay``: the lasting change is
settled) the :class:`EventClassifier` weighs the evidence, in this order:

1. **declared operations** (:class:`Operation`, from a SCADA log: ``asset,time,action``): an
   operation of any asset within ``operation_window`` seconds of the onset explains the alarm
   (``other``);
2. **rises**: a burst only lowers heads. Meters whose lasting change is a rise beyond
   ``rise_tolerance`` (m): all of them, a pump start, a valve opening or a falling demand; some,
   heads rising on one side and falling on the other, an operation splitting the network (a
   valve or pump between the sides; the reason names one with an end on each side, or else
   beside the first meter to alarm, when ``asset_nodes`` holds it) (``other``);
3. **where it started**: the first meter to alarm is an asset's node (a pump's outlet, a valve's
   side) and the lasting drop fits best a pipe that ends there: a pump trip or a valve closure
   (``other``). (At coarse capture intervals many meters alarm on the same reading, and the
   first is the one with the largest change: the lasting drop must agree.)
4. **a drop large enough to be sure of**: a burst lowers heads beyond ``rise_tolerance`` at
   :data:`MIN_FALLING` meters at least; a smaller drop (a demand change, a small leak) is
   ``unsure``;
5. **the lasting drop's fit to a burst**: the drop ``d`` fits ``k s_p`` (the signature
   localizer's fit, :func:`burstloc.localize.signature.fit_signatures`) with a scale ``k`` of at
   least ``min_scale`` (a burst's outflow, relative to the signatures' reference burst) and a
   relative residual ``rms(d - k s_p) / rms(d)`` of at most ``max_residual``; a smaller drop (a
   demand change, a small leak) or one that fits no pipe is ``unsure``; otherwise ``burst``.

Only ``burst`` decisions are reported as bursts; the others are events. The thresholds come from
the calibration procedure of :func:`burstloc.experiments.specificity.calibrate_classifier`
(on simulated bursts, never on the events it is evaluated with), stored as a
:class:`ClassifierConfig` JSON document. Numpy only; on the live path.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from burstloc._atomic import write_json
from burstloc._validate import Fields, attributes, check_number, check_string, read_json
from burstloc.constants import MeterModel
from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.evidence import BurstEvidence, evidence_at
from burstloc.localize.signature import SignatureLocalizer, fit_signatures

__all__ = [
    "CLASSES",
    "CLASSIFIER_FORMAT",
    "Classification",
    "ClassifierConfig",
    "EventClassifier",
    "Operation",
    "classify_alarms",
    "read_operations",
]

#: The three answers.
CLASSES = ("burst", "other", "unsure")
Label = Literal["burst", "other", "unsure"]

CLASSIFIER_FORMAT = "burstloc-classifier/1"
"""Format tag of a classifier configuration file."""

#: A burst lowers the head beyond the rise tolerance (the calibrated uncertainty of a lasting
#: change) at this many meters at least; a smaller, more local drop is ``unsure``.
MIN_FALLING = 2

#: The thresholds, by name.
THRESHOLDS = ("max_residual", "min_scale", "rise_tolerance")

#: Seconds around the onset within which a declared operation explains an alarm (default).
OPERATION_WINDOW = 60.0


@dataclass(frozen=True)
class Classification:
    """The class of one alarm, why (``reason``, for the operator) and the evidence weighed."""

    label: Label
    reason: str
    evidence: Mapping[str, Any] = field(default_factory=dict)

    @property
    def is_burst(self) -> bool:
        """Whether the alarm is reported as a burst."""
        return self.label == "burst"

    def to_json(self) -> dict[str, Any]:
        """``{"class", "reason", "evidence"}``."""
        return {"class": self.label, "reason": self.reason, "evidence": dict(self.evidence)}


@dataclass(frozen=True)
class Operation:
    """A declared operation: ``asset`` (valve, pump, junction), ``time`` (s, the readings'
    clock) and ``action`` (free text, e.g. ``close``)."""

    asset: str
    time: float
    action: str


def read_operations(path: str | os.PathLike[str]) -> list[Operation]:
    """Read a CSV of declared operations with header ``asset,time,action``.

    Raises:
        InputError: a missing column, or a row whose time is not a finite number (named by
            line).
    """
    with Path(path).open(newline="", encoding="utf-8") as handle:
        rows = csv.DictReader(handle)
        missing = {"asset", "time", "action"} - set(rows.fieldnames or ())
        if missing:
            raise InputError(f"{path}: operations need columns asset,time,action: {missing}")
        out = []
        for line, row in enumerate(rows, start=2):
            try:
                t = float(row["time"])
            except (TypeError, ValueError):
                t = math.nan
            if not math.isfinite(t) or not row["asset"]:
                raise InputError(f"{path}: line {line}: bad operation {dict(row)}")
            out.append(Operation(row["asset"], t, row["action"] or ""))
    return out


@dataclass(frozen=True)
class ClassifierConfig:
    """Thresholds (from the calibration procedure) and the network's asset nodes.

    ``max_residual``: largest relative residual of a burst's signature fit; ``min_scale``:
    smallest burst scale reported with confidence; ``rise_tolerance`` (m): a lasting rise larger
    than this is not a burst's. ``intervals`` holds the same three per capture interval
    (``{"2": {"max_residual": ..., ...}}``; the top-level values serve the others).
    ``asset_nodes``: junction -> the valve or pump beside it; ``operation_window`` (s);
    ``provenance``: how the thresholds were found.
    """

    max_residual: float
    min_scale: float
    rise_tolerance: float
    asset_nodes: Mapping[str, str] = field(default_factory=dict)
    operation_window: float = OPERATION_WINDOW
    provenance: Mapping[str, Any] = field(default_factory=dict)
    intervals: Mapping[str, Mapping[str, float]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        _check_thresholds(self.max_residual, self.min_scale, self.rise_tolerance, "")
        check_number(self.operation_window, "operation_window", low=0, high=86_400.0)
        for node, asset in self.asset_nodes.items():
            check_string(node, "asset_nodes")
            check_string(asset, f"asset_nodes.{node}")
        for ci, values in self.intervals.items():
            where = f"intervals.{ci}."
            check_number(float(ci), f"intervals.{ci}", low=0, low_open=True, high=3600.0)
            if not isinstance(values, Mapping) or set(values) != set(THRESHOLDS):
                raise ConfigError(f"{where[:-1]} must hold exactly {THRESHOLDS}")
            _check_thresholds(
                values["max_residual"], values["min_scale"], values["rise_tolerance"], where
            )

    def thresholds(self, capture_interval: float) -> tuple[float, float, float]:
        """``(max_residual, min_scale, rise_tolerance)`` at ``capture_interval``."""
        for ci, values in self.intervals.items():
            if math.isclose(float(ci), capture_interval, rel_tol=1e-9):
                return values["max_residual"], values["min_scale"], values["rise_tolerance"]
        return self.max_residual, self.min_scale, self.rise_tolerance

    def to_json(self) -> dict[str, Any]:
        """The JSON document (format :data:`CLASSIFIER_FORMAT`)."""
        return {
            "format": CLASSIFIER_FORMAT,
            **attributes(self, "max_residual", "min_scale", "rise_tolerance"),
            "asset_nodes": dict(self.asset_nodes),
            "operation_window": self.operation_window,
            "intervals": {ci: dict(v) for ci, v in self.intervals.items()},
            "provenance": dict(self.provenance),
        }

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the configuration as JSON (atomically)."""
        return write_json(path, self.to_json())

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> ClassifierConfig:
        """Read a file written by :meth:`save`.

        Raises:
            ConfigError: not a classifier file, or a field missing or out of range (named).
        """
        doc = Fields(read_json(path, "classifier file"), os.fspath(path))
        with doc.checking():
            if doc.get("format") != CLASSIFIER_FORMAT:
                raise ConfigError(f"format must be {CLASSIFIER_FORMAT!r}")
        return doc.build(
            cls,
            ("max_residual", "min_scale", "rise_tolerance"),
            asset_nodes=doc.optional_object("asset_nodes"),
            operation_window=doc.data.get("operation_window", OPERATION_WINDOW),
            provenance=doc.optional_object("provenance"),
            intervals=doc.optional_object("intervals"),
        )


def _check_thresholds(max_residual: Any, min_scale: Any, rise_tolerance: Any, where: str) -> None:
    check_number(max_residual, f"{where}max_residual", low=0, low_open=True, high=10.0)
    check_number(min_scale, f"{where}min_scale", low=0, high=1e6)
    check_number(rise_tolerance, f"{where}rise_tolerance", low=0, high=1e3)


def _first_meter(evidence: BurstEvidence) -> str | None:
    """The meter whose change started first (ties: the larger change)."""
    if not evidence.alarms:
        return None
    first = min(evidence.alarms.values(), key=lambda a: (a.start, -abs(a.amplitude)))
    return first.meter


def _split_reason(
    rising: Sequence[str], falling: Sequence[str], first: str | None, assets: Mapping[str, str]
) -> str:
    """Why heads rising at some meters and falling at others is another event, naming what is
    known: the valve or pump (``assets``: junction -> link) with an end on each side, else the
    one beside the first meter to alarm, else no asset (the network may have no valve)."""
    heads = f"heads rose at {', '.join(rising[:3])} and fell at {', '.join(falling[:3])}"
    for asset in dict.fromkeys(assets.values()):
        ends = {node for node, a in assets.items() if a == asset}
        if ends & set(rising) and ends & set(falling):
            return f"{heads}, on either side of link {asset}: an operation of {asset}"
    splitting = "an operation splitting the network (one side rose, the other fell)"
    beside = assets.get(first or "")
    if beside is not None:
        return f"{heads}, the transient starting at {first}, beside link {beside}: {splitting}"
    return f"{heads}: {splitting}"


class EventClassifier:
    """Classify one alarm's evidence as ``burst``, ``other`` or ``unsure`` (module docstring).

    ``signature`` is the signature localizer whose drop estimate and signatures are used;
    ``operations`` the declared operations (default none).
    """

    def __init__(
        self,
        config: ClassifierConfig,
        signature: SignatureLocalizer,
        operations: Sequence[Operation] = (),
    ) -> None:
        self.config = config
        self.signature = signature
        self.operations = list(operations)

    @classmethod
    def of(
        cls,
        config: ClassifierConfig,
        localizers: Mapping[str, Any],
        operations: Sequence[Operation] = (),
    ) -> EventClassifier:
        """The classifier over the ``"signature"`` localizer of ``localizers``.

        Raises:
            ConfigError: there is no signature localizer.
        """
        signature = localizers.get("signature")
        if not isinstance(signature, SignatureLocalizer):
            raise ConfigError("classifying alarms needs the signature localizer")
        return cls(config, signature, operations)

    def features(self, evidence: BurstEvidence) -> dict[str, Any]:
        """What the classification weighs: the lasting drop per meter and its best burst fit
        (``scale``, ``residual`` relative, ``pipe``), the rising meters and the first meter."""
        drop = self.signature.drop(evidence)
        meters = self.signature.signatures.meters
        fits = [fit_signatures(drop, s.matrix) for s in self.signature.signature_sets]
        scale = np.stack([k for k, _ in fits])
        rms = np.stack([r for _, r in fits])
        where = np.unravel_index(int(np.argmin(rms)), rms.shape)
        size = float(np.sqrt(np.mean(drop**2)))
        tol = self.config.thresholds(evidence.capture_interval)[2]
        return {
            "scale": float(scale[where]),
            "residual": float(rms[where]) / size if size > 0 else math.inf,
            "pipe": self.signature.signatures.pipes[int(where[1])],
            "largest_drop_m": float(drop.max()),
            "largest_rise_m": float(-drop.min()),
            "rising": [m for m, d in zip(meters, drop, strict=True) if d < -tol],
            "falling": [m for m, d in zip(meters, drop, strict=True) if d > tol],
            "first_meter": _first_meter(evidence),
        }

    def classify(self, evidence: BurstEvidence) -> Classification:
        """The class of the alarm whose evidence (readings up to the decision time) is given."""
        cfg = self.config
        max_residual, min_scale, tol = cfg.thresholds(evidence.capture_interval)
        declared = [
            op for op in self.operations if abs(op.time - evidence.onset) <= cfg.operation_window
        ]
        if declared:
            op = min(declared, key=lambda o: abs(o.time - evidence.onset))
            reason = f"declared operation: {op.action} {op.asset} at t = {op.time:g} s"
            return Classification("other", reason, {"operation": op.asset})
        f = self.features(evidence)
        evidence_json = {k: v for k, v in f.items() if not isinstance(v, list)}
        evidence_json.update(rising=len(f["rising"]), falling=len(f["falling"]))
        if f["rising"] and not f["falling"]:
            reason = "heads rose everywhere (a pump start, a valve opening or a demand falling)"
            return Classification("other", reason, evidence_json)
        if f["rising"]:
            reason = _split_reason(f["rising"], f["falling"], f["first_meter"], cfg.asset_nodes)
            return Classification("other", reason, evidence_json)
        first = f["first_meter"] or ""
        asset = cfg.asset_nodes.get(first)
        if asset is not None and first in self.signature.signatures.endpoints[f["pipe"]]:
            reason = (
                f"the transient started at {first}, beside {asset}, and the lasting drop "
                f"points there (pipe {f['pipe']})"
            )
            return Classification("other", reason, evidence_json)
        if len(f["falling"]) < MIN_FALLING:
            reason = (
                f"no lasting drop beyond {tol:.3g} m at {MIN_FALLING} meters "
                f"(largest {f['largest_drop_m']:.3g} m): a small, local change"
            )
            return Classification("unsure", reason, evidence_json)
        if f["scale"] < min_scale:
            reason = f"a small lasting drop (scale {f['scale']:.3g} < {min_scale:.3g})"
            return Classification("unsure", reason, evidence_json)
        if f["residual"] > max_residual:
            reason = f"the drop fits no burst (residual {f['residual']:.3g})"
            return Classification("unsure", reason, evidence_json)
        reason = f"a lasting drop that fits a burst on pipe {f['pipe']}"
        return Classification("burst", reason, evidence_json)


def classify_alarms(
    classifier: EventClassifier,
    meters: Sequence[str],
    times: np.ndarray,
    readings: np.ndarray,
    alarms: Sequence[Any],
    calibration: Any,
    meter_model: MeterModel,
    decided: float,
) -> Classification:
    """Classify a detector bank's alarms on these readings at reading time ``decided`` (the
    signature's decision time, ``decision_time("signature", ...)`` of
    :mod:`burstloc.localize.decide`: the lasting change has settled), the evidence built as
    the localizers build theirs.

    Raises:
        InputError: no alarm.
    """
    evidence = evidence_at(decided, meters, times, readings, alarms, calibration, meter_model)
    return classifier.classify(evidence)
