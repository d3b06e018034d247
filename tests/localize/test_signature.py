"""The signature localizer: signature sets, the free-scale fit, the estimators (numpy only; the
WNTR computation of the signatures is tested in tests/sim/test_signatures.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, InputError
from burstloc.localize.evidence import BurstEvidence
from burstloc.localize.signature import (
    SignatureLocalizer,
    SignatureSet,
    fit_signatures,
    rank_drop,
)
from ringing import ringing


def _synthetic(pipes: int = 4, meters: int = 6, seed: int = 1) -> SignatureSet:
    rng = np.random.default_rng(seed)
    return SignatureSet(
        network_hash="sha256:test",
        meters=tuple(f"m{j}" for j in range(meters)),
        pipes=tuple(f"p{i}" for i in range(pipes)),
        endpoints={f"p{i}": (f"a{i}", f"b{i}") for i in range(pipes)},
        matrix=rng.uniform(0.05, 1.0, size=(pipes, meters)),
        baseline=np.full(meters, 50.0),
        params={},
    )


def test_fit_recovers_scale_and_pipe() -> None:
    sig = _synthetic()
    drop = 2.5 * sig.matrix[2]
    k, rms = fit_signatures(drop, sig.matrix)
    assert k[2] == pytest.approx(2.5)
    assert rms[2] == pytest.approx(0.0, abs=1e-12)
    assert np.all(rms[[0, 1, 3]] > 1e-3)
    ranking = rank_drop(drop, sig)
    assert ranking.best is not None and ranking.best.pipe == "p2"
    assert ranking.best.score == pytest.approx(0.0, abs=1e-12)
    assert (ranking.best.start, ranking.best.end) == ("a2", "b2")


def test_fit_scale_is_never_negative() -> None:
    sig = _synthetic()
    drop = -sig.matrix[1]  # a rise: no burst size explains it
    k, rms = fit_signatures(drop, sig.matrix)
    assert np.all(k == 0.0)
    assert rms == pytest.approx(np.full(4, math.sqrt(np.mean(drop**2))))


def test_fit_rejects_mismatched_shapes() -> None:
    with pytest.raises(InputError):
        fit_signatures(np.ones(3), np.ones((2, 4)))
    with pytest.raises(InputError):
        fit_signatures(np.array([1.0, np.nan]), np.ones((2, 2)))


@pytest.mark.parametrize("name", ["sig.json", "sig.npz"])
def test_signature_set_round_trip_and_subset(tmp_path: Path, name: str) -> None:
    sig = _synthetic()
    path = tmp_path / name
    sig.save(path)
    back = SignatureSet.load(path)
    assert back.pipes == sig.pipes and back.meters == sig.meters
    assert back.endpoints == sig.endpoints and back.params == sig.params
    np.testing.assert_array_equal(back.matrix, sig.matrix)  # bit for bit, either way
    np.testing.assert_array_equal(back.baseline, sig.baseline)
    sub = back.for_meters(["m3", "m0"])
    np.testing.assert_array_equal(sub.matrix, sig.matrix[:, [3, 0]])
    with pytest.raises(InputError, match="m9"):
        back.for_meters(["m9"])
    if name.endswith(".npz"):
        np.savez(path, **{**sig.to_arrays(), "format": np.asarray("other")})
    else:
        path.write_text(json.dumps({"format": "other"}))
    with pytest.raises(InputError, match="not a signature file"):
        SignatureSet.load(path)


def test_signature_set_npz_is_checked(tmp_path: Path) -> None:
    sig = _synthetic()
    # a damaged or foreign file is an InputError naming the problem
    arrays = sig.to_arrays()
    np.savez(tmp_path / "nan.npz", **{**arrays, "matrix": np.full_like(sig.matrix, np.nan)})
    with pytest.raises(InputError, match="'matrix' holds NaN"):
        SignatureSet.load(tmp_path / "nan.npz")
    np.savez(tmp_path / "short.npz", **{k: v for k, v in arrays.items() if k != "pipes"})
    with pytest.raises(InputError, match="no array 'pipes'"):
        SignatureSet.load(tmp_path / "short.npz")
    np.savez(tmp_path / "flat.npz", **{**arrays, "matrix": sig.matrix.ravel()})
    with pytest.raises(InputError, match="'matrix' must be 2-dimensional"):
        SignatureSet.load(tmp_path / "flat.npz")
    (tmp_path / "text.npz").write_text("not a zip")
    with pytest.raises(InputError, match=r"not an \.npz file"):
        SignatureSet.load(tmp_path / "text.npz")


def test_signature_sets_must_agree() -> None:
    one, other = _synthetic(meters=6), _synthetic(meters=5)
    drop = one.matrix[1]
    assert [p.pipe for p in rank_drop(drop, [one])] == [p.pipe for p in rank_drop(drop, one)]
    with pytest.raises(ConfigError, match="disagree"):
        rank_drop(drop, [one, other])
    with pytest.raises(ConfigError, match="at least one"):
        SignatureLocalizer([])
    loc = SignatureLocalizer([one, _synthetic(meters=6, seed=2)])
    assert loc.signatures is loc.signature_sets[0] and len(loc.signature_sets) == 2


@pytest.mark.parametrize("model", ["instantaneous", "interval-averaged"])
def test_localizer_finds_the_pipe_from_readings(model: str) -> None:
    sig = _synthetic(pipes=6, meters=8, seed=4)
    dt = 5.0
    t = np.arange(0.0, 160.0 + 1e-9, dt)
    onset = 10.0
    rng = np.random.default_rng(5)
    shapes = rng.uniform(-0.5, 0.5, size=(2, 8))
    after = ringing(t - onset, sig.baseline - 0.7 * sig.matrix[4], shapes, dt, model)
    readings = np.where((t <= onset)[:, None], sig.baseline[None, :], after)
    evidence = BurstEvidence(
        meters=sig.meters,
        times=t,
        readings=readings,
        onset=onset,
        capture_interval=dt,
        meter_model=model,  # type: ignore[arg-type]
    )
    loc = SignatureLocalizer(sig)
    drop = loc.drop(evidence)
    np.testing.assert_allclose(drop, 0.7 * sig.matrix[4], atol=0.01)
    ranking = loc.rank(evidence)
    assert ranking.best is not None and ranking.best.pipe == "p4"
    assert len(ranking) == 6


def test_localizer_needs_a_baseline_and_settled_readings() -> None:
    sig = _synthetic()
    t = np.arange(20.0, 200.0, 10.0)
    evidence = BurstEvidence(
        meters=sig.meters,
        times=t,
        readings=np.tile(sig.baseline, (t.size, 1)),
        onset=10.0,
        capture_interval=10.0,
    )
    with pytest.raises(InputError, match="before the burst"):
        SignatureLocalizer(sig).rank(evidence)
    with pytest.raises(ConfigError):
        SignatureLocalizer(sig, settle=100.0, decision_delay=50.0)
    with pytest.raises(ConfigError):
        SignatureLocalizer(sig, estimator="best")  # type: ignore[arg-type]
