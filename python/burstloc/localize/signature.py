"""The *signature* localizer: match the meters' lasting pressure drop to each pipe's signature.

A burst on pipe ``p`` moves the network to a new steady state. Its *signature* ``s_p(x)`` is the
vector of steady-state head drops at the meters caused by an emitter at position ``x`` along the
pipe, computed offline, once per network, from the hydraulic model (EPANET steady states through
WNTR: :mod:`burstloc.sim.signatures.compute`) and stored with the calibrated configuration
(:class:`burstloc.localize.model.LocalizationModel`): one :class:`SignatureSet` per position, by
default at the candidate positions 0.1, ..., 0.9 of :data:`burstloc.constants.CANDIDATE_POSITIONS`,
the arrival localizer's. At run time the localizer estimates the observed drop
``d = baseline - new level`` per meter from the readings (:mod:`burstloc.localize.steady_level`),
fits ``d ~ k * s_p(x)`` with a free scale ``k >= 0`` (the burst size is unknown; closed-form least
squares) and ranks pipes by the RMS residual of their best position: ``score = -min_x RMS``. A
burst near a pipe's end looks like a burst at that end node, so one mid-point signature per pipe
misranks off-centre bursts.

Numpy only: this module (:class:`SignatureSet`, :class:`SignatureLocalizer`, :func:`rank_drop`)
imports neither WNTR nor the simulator.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc._atomic import write_json, write_npz
from burstloc._validate import read_json, read_npz
from burstloc.constants import SIGNATURE_DECISION_DELAY
from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.evidence import BurstEvidence, RankedPipe, Ranking
from burstloc.localize.steady_level import (
    ESTIMATORS,
    EstimatorName,
    baseline_levels,
    estimate_levels,
)

__all__ = [
    "SIGNATURE_FORMAT",
    "SignatureLocalizer",
    "SignatureSet",
    "fit_signatures",
    "rank_drop",
]

SIGNATURE_FORMAT = "burstloc-signatures/1"
"""Format tag written into every signature file (JSON or ``.npz``)."""

_NPZ_ARRAYS = {
    "format": ("U", 0),
    "network_hash": ("U", 0),
    "meters": ("U", 1),
    "pipes": ("U", 1),
    "endpoints": ("U", 2),
    "baseline": ("f", 1),
    "matrix": ("f", 2),
    "params": ("U", 0),
}
"""The arrays of a signature file in NumPy's ``.npz`` form (kind, dimensions): the JSON
document's fields, ``endpoints`` as a (pipes, 2) table in ``pipes`` order and ``params`` as JSON
text."""

DEFAULT_SETTLE = 60.0
"""Seconds after the onset skipped before estimating the new level: TSNet's slowest network mode
(about 16 s period on paper15) starts at metres and decays with a ~30 s time constant."""

DEFAULT_DECISION_DELAY = SIGNATURE_DECISION_DELAY
"""Seconds after the onset at which the signature localizer answers
(:data:`burstloc.constants.SIGNATURE_DECISION_DELAY`)."""


@dataclass(frozen=True)
class SignatureSet:
    """Burst signatures of one network: ``matrix[i, j]`` is the steady head drop (m) at
    ``meters[j]`` for the reference burst at the mid-point of ``pipes[i]``.

    ``endpoints[pipe]`` is ``(start, end)`` in the base steady state's flow direction;
    ``baseline[j]`` is the base steady head at ``meters[j]``; ``params`` records how the
    signatures were computed (burst coefficient, position, demand model).
    """

    network_hash: str
    meters: tuple[str, ...]
    pipes: tuple[str, ...]
    endpoints: Mapping[str, tuple[str, str]]
    matrix: NDArray[np.float64]
    baseline: NDArray[np.float64]
    params: Mapping[str, Any]

    def __post_init__(self) -> None:
        matrix = np.asarray(self.matrix, dtype=np.float64)
        baseline = np.asarray(self.baseline, dtype=np.float64)
        if matrix.shape != (len(self.pipes), len(self.meters)):
            raise InputError(
                f"signature matrix must be (pipes, meters) = ({len(self.pipes)}, "
                f"{len(self.meters)}), got {matrix.shape}"
            )
        if baseline.shape != (len(self.meters),):
            raise InputError(f"baseline must have one head per meter, got {baseline.shape}")
        if not (np.all(np.isfinite(matrix)) and np.all(np.isfinite(baseline))):
            raise InputError("signatures must be finite")
        missing = [p for p in self.pipes if p not in self.endpoints]
        if missing:
            raise InputError(f"no end nodes for pipe(s) {missing}")
        if len(set(self.meters)) != len(self.meters) or len(set(self.pipes)) != len(self.pipes):
            raise InputError("duplicate meter or pipe in a signature set")
        matrix.setflags(write=False)
        baseline.setflags(write=False)
        object.__setattr__(self, "matrix", matrix)
        object.__setattr__(self, "baseline", baseline)
        object.__setattr__(self, "meters", tuple(self.meters))
        object.__setattr__(self, "pipes", tuple(self.pipes))
        object.__setattr__(
            self, "endpoints", {p: (str(a), str(b)) for p, (a, b) in self.endpoints.items()}
        )
        object.__setattr__(self, "params", dict(self.params))

    def for_meters(self, meters: Sequence[str]) -> SignatureSet:
        """The same signatures restricted to (and ordered like) ``meters``."""
        index = {m: j for j, m in enumerate(self.meters)}
        unknown = [m for m in meters if m not in index]
        if unknown:
            raise InputError(f"no signature for meter(s) {unknown}")
        cols = [index[m] for m in meters]
        return SignatureSet(
            network_hash=self.network_hash,
            meters=tuple(meters),
            pipes=self.pipes,
            endpoints=self.endpoints,
            matrix=self.matrix[:, cols],
            baseline=self.baseline[cols],
            params=self.params,
        )

    def to_json(self) -> dict[str, Any]:
        """JSON-ready dictionary (see :data:`SIGNATURE_FORMAT`)."""
        return {
            "format": SIGNATURE_FORMAT,
            "network_hash": self.network_hash,
            "meters": list(self.meters),
            "pipes": list(self.pipes),
            "endpoints": {p: list(self.endpoints[p]) for p in self.pipes},
            "baseline": self.baseline.tolist(),
            "matrix": self.matrix.tolist(),
            "params": dict(self.params),
        }

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> SignatureSet:
        """Inverse of :meth:`to_json`; a malformed document raises ``InputError``."""
        if data.get("format") != SIGNATURE_FORMAT:
            raise InputError(
                f"not a signature file (format {data.get('format')!r}, want {SIGNATURE_FORMAT!r})"
            )
        try:
            return cls(
                network_hash=str(data["network_hash"]),
                meters=tuple(data["meters"]),
                pipes=tuple(data["pipes"]),
                endpoints={p: (e[0], e[1]) for p, e in data["endpoints"].items()},
                matrix=np.asarray(data["matrix"], dtype=np.float64).reshape(
                    len(data["pipes"]), len(data["meters"])
                ),
                baseline=np.asarray(data["baseline"], dtype=np.float64),
                params=dict(data.get("params", {})),
            )
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise InputError(f"malformed signature file: {exc}") from exc

    def to_arrays(self) -> dict[str, NDArray[Any]]:
        """The ``.npz`` form (:data:`_NPZ_ARRAYS`): the matrices stored as binary doubles."""
        import json

        return {
            "format": np.asarray(SIGNATURE_FORMAT),
            "network_hash": np.asarray(self.network_hash),
            "meters": np.asarray(self.meters, dtype=str).reshape(len(self.meters)),
            "pipes": np.asarray(self.pipes, dtype=str).reshape(len(self.pipes)),
            "endpoints": np.asarray([self.endpoints[p] for p in self.pipes], dtype=str).reshape(
                len(self.pipes), 2
            ),
            "baseline": self.baseline,
            "matrix": self.matrix,
            "params": np.asarray(json.dumps(dict(self.params), sort_keys=True)),
        }

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, NDArray[Any]]) -> SignatureSet:
        """Inverse of :meth:`to_arrays`; arrays that do not fit raise ``InputError``."""
        import json

        if str(arrays["format"][()]) != SIGNATURE_FORMAT:
            raise InputError(f"not a signature file (format {str(arrays['format'][()])!r})")
        pipes = tuple(str(p) for p in arrays["pipes"])
        endpoints = arrays["endpoints"]
        if endpoints.shape != (len(pipes), 2):
            raise InputError(f"endpoints must be (pipes, 2), got {endpoints.shape}")
        try:
            params = json.loads(str(arrays["params"][()]))
        except ValueError as exc:
            raise InputError(f"malformed signature parameters: {exc}") from None
        if not isinstance(params, dict):
            raise InputError("signature parameters must be a JSON object")
        return cls(
            network_hash=str(arrays["network_hash"][()]),
            meters=tuple(str(m) for m in arrays["meters"]),
            pipes=pipes,
            endpoints={p: (str(a), str(b)) for p, (a, b) in zip(pipes, endpoints, strict=True)},
            matrix=arrays["matrix"],
            baseline=arrays["baseline"],
            params=params,
        )

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the signatures atomically: NumPy's ``.npz`` when ``path`` ends in ``.npz``
        (binary doubles: a fraction of the JSON's size and reading time on large networks),
        JSON otherwise."""
        if os.fspath(path).endswith(".npz"):
            write_npz(path, self.to_arrays())
        else:
            write_json(path, self.to_json(), indent=None)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> SignatureSet:
        """Read a file written by :meth:`save` (``.npz`` or JSON, by the file's suffix)."""
        try:
            if os.fspath(path).endswith(".npz"):
                return cls.from_arrays(read_npz(path, "signature file", _NPZ_ARRAYS))
            data = read_json(path, "signature file")
        except ConfigError as exc:
            raise InputError(str(exc)) from None
        return cls.from_json(data)


def _as_sets(signatures: SignatureSet | Sequence[SignatureSet]) -> tuple[SignatureSet, ...]:
    """One or several signature sets of the same meters and pipes, as a non-empty tuple."""
    sets = (signatures,) if isinstance(signatures, SignatureSet) else tuple(signatures)
    if not sets:
        raise ConfigError("at least one signature set is needed")
    first = sets[0]
    for other in sets[1:]:
        if other.meters != first.meters or other.pipes != first.pipes:
            raise ConfigError(
                "signature sets disagree on meters or pipes: "
                f"position {other.params.get('position')} vs {first.params.get('position')}"
            )
    return sets


def fit_signatures(
    drop: NDArray[np.float64], matrix: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Fit ``drop ~ k_i * matrix[i]`` with ``k_i >= 0`` for every row; return ``(k, rms)``.

    Closed form: ``k_i = max(0, <d, s_i> / <s_i, s_i>)``; ``rms_i`` is the root mean square of
    ``d - k_i s_i`` over the meters. A zero signature fits with ``k = 0``.
    """
    d = np.asarray(drop, dtype=np.float64)
    s = np.asarray(matrix, dtype=np.float64)
    if d.ndim != 1 or s.ndim != 2 or s.shape[1] != d.size or d.size == 0:
        raise InputError(f"drop (M,) and signatures (P, M) do not match: {d.shape}, {s.shape}")
    if not np.all(np.isfinite(d)):
        raise InputError("the drop vector must be finite")
    norms = np.einsum("pm,pm->p", s, s)
    dots = s @ d
    k = np.where(norms > 0, np.maximum(dots, 0.0) / np.where(norms > 0, norms, 1.0), 0.0)
    resid = d[None, :] - k[:, None] * s
    rms = np.sqrt(np.mean(resid**2, axis=1))
    return k, rms


def rank_drop(
    drop: NDArray[np.float64], signatures: SignatureSet | Sequence[SignatureSet]
) -> Ranking:
    """Rank pipes by how well ``drop`` (per meter, m) fits their signature.

    With several sets (positions along each pipe), a pipe scores its best position's fit.
    """
    sets = _as_sets(signatures)
    rms = np.min(np.stack([fit_signatures(drop, s.matrix)[1] for s in sets]), axis=0)
    first = sets[0]
    return Ranking(
        RankedPipe(p, *first.endpoints[p], score=-float(r))
        for p, r in zip(first.pipes, rms, strict=True)
    )


class SignatureLocalizer:
    """Rank pipes by the fit of the observed lasting drop to their burst signatures.

    ``signatures`` is one :class:`SignatureSet` or several (positions along each pipe, e.g. a
    stored model's :attr:`~burstloc.localize.model.LocalizationModel.signature_sets`) of the same
    meters and pipes; :attr:`signatures` is the first, :attr:`signature_sets` all of them.

    ``settle`` seconds after the onset are skipped (the fast transient); the new level of each
    meter is estimated by ``estimator`` from the readings between ``onset + settle`` and the
    decision time; the baseline is the mean of the readings before the onset. ``decision_delay``
    is how long after the onset the localizer wants to answer: the caller hands it the readings up
    to ``onset + decision_delay``.
    """

    def __init__(
        self,
        signatures: SignatureSet | Sequence[SignatureSet],
        *,
        estimator: EstimatorName = "damped-fit",
        settle: float = DEFAULT_SETTLE,
        decision_delay: float = DEFAULT_DECISION_DELAY,
        modes: int = 3,
    ) -> None:
        if estimator not in ESTIMATORS:
            raise ConfigError(f"unknown estimator {estimator!r}; use one of {sorted(ESTIMATORS)}")
        if not (math.isfinite(settle) and settle >= 0):
            raise ConfigError(f"settle must be >= 0 s, got {settle}")
        if not (math.isfinite(decision_delay) and decision_delay > settle):
            raise ConfigError(f"decision_delay must be > settle ({settle} s), got {decision_delay}")
        self.signature_sets = _as_sets(signatures)
        self.signatures = self.signature_sets[0]
        self.estimator: EstimatorName = estimator
        self.settle = float(settle)
        self.decision_delay = float(decision_delay)
        if modes < 0:
            raise ConfigError(f"modes must be >= 0, got {modes}")
        self.modes = int(modes)

    def drop(self, evidence: BurstEvidence) -> NDArray[np.float64]:
        """The observed lasting drop (baseline - new level) per signature meter, in metres."""
        cols = evidence.columns(self.signatures.meters)
        values = evidence.readings[:, cols]
        times = evidence.times
        # the onset stamp is the detector's start of the change: the last reading before it
        pre = times <= evidence.onset
        baseline = baseline_levels(values[pre])
        post = times >= evidence.onset + self.settle
        level = estimate_levels(
            times[post],
            values[post],
            capture_interval=evidence.capture_interval,
            meter_model=evidence.meter_model,
            method=self.estimator,
            modes=self.modes,
        )
        return baseline - level

    def rank(self, evidence: BurstEvidence) -> Ranking:
        """Every pipe, best first, scored by minus the RMS residual of the signature fit (m)."""
        return rank_drop(self.drop(evidence), self.signature_sets)
