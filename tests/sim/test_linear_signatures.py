"""Burst signatures from one factorization of the linearized steady state, checked against
EPANET's own steady states on small real INP files with every kind of link."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from burstloc.constants import EXACT_SIGNATURES_UP_TO, HYBRID_SIGNATURES_UP_TO
from burstloc.exceptions import ConfigError
from burstloc.sim.signatures.compute import (
    cached_signature_sets,
    compute_signatures,
    linear_signature_sets,
    signature_method,
)

REPO = Path(__file__).resolve().parents[2]
PAPER15 = REPO / "networks" / "paper15.inp"
NET3 = REPO / "networks" / "public" / "Net3.inp"

#: R1 -> pump -> J1 = (B, B2 side by side) => J2 -> {valve} -> J3 -> J4 -> J5 -> J2 (a loop),
#: a tank on J4 and a dead end J6 with an emitter.
NETWORK = """\
[JUNCTIONS]
 J0  0   0
 J1  10  2
 J2  10  3
 J2a 10  0
 J3  5   3
 J4  0   2
 J5  0   4
 J6  2   1

[RESERVOIRS]
 R1  {head}

[TANKS]
 T1  0  30  0  50  10  0

[PIPES]
 A   R1  J0  150  300  100  0  Open
 B   J1  J2  200  250  100  0  Open
 B2  J1  J2  210  200  100  0  Open
 C   J2  J2a 120  250  100  0  Open
 D   J3  J4  150  200  100  0  Open
 E   J4  J5  180  150  100  0  Open
 F   J5  J2  220  150  100  0  Open
 G   J4  T1  100  200  100  0  Open
 H   J5  J6  90   100  100  0  {h_status}
{extra_pipes}
[PUMPS]
 P1  J0  J1  {pump}

[VALVES]
 V1  J2a J3  250  {valve}  0

[CURVES]
 C1  60  50

[EMITTERS]
 J6  0.5

[OPTIONS]
 Units     LPS
 Headloss  {headloss}
 Required Pressure  0.1
 Accuracy  0.000000001
 Trials    500
 Unbalanced Continue 50

[END]
"""

PLAIN = {
    "head": 20,
    "pump": "HEAD C1",
    "valve": "TCV  2",
    "headloss": "H-W",
    "h_status": "Open",
    "extra_pipes": "",
}

VARIANTS = {
    "pump curve, throttle valve": {},
    "pump by power": {"pump": "POWER 20"},
    "active PRV": {"valve": "PRV  30"},
    "active PSV": {"valve": "PSV  35"},
    "active flow control": {"valve": "FCV  5"},
    "closed pipe": {"h_status": "Closed"},
    "Darcy-Weisbach": {"headloss": "D-W"},
}


def write(tmp_path: Path, name: str, **changes: str | float) -> Path:
    path = tmp_path / f"{name.replace(' ', '_').replace(',', '')}.inp"
    text = NETWORK.format(**{**PLAIN, **changes})
    if changes.get("headloss") == "D-W":  # roughness in mm
        text = text.replace("  100  0  ", "  0.1  0  ")
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_linear_signatures_are_the_small_burst_limit_of_epanets(
    tmp_path: Path, variant: str
) -> None:
    path = write(tmp_path, variant, **VARIANTS[variant])
    coeff = 1e-5  # a burst small enough that EPANET's answer is linear in it
    for position in (0.5, 0.2):
        exact = compute_signatures(path, burst_coeff=coeff, position=position)
        [linear] = linear_signature_sets(path, positions=[position], burst_coeff=coeff)
        assert linear.pipes == exact.pipes and linear.meters == exact.meters
        assert dict(linear.endpoints) == dict(exact.endpoints)
        assert np.array_equal(linear.baseline, exact.baseline)
        assert linear.params["method"] == "linear"
        scale = float(np.abs(exact.matrix).max())
        assert scale > 1e-5  # the burst is heard
        assert np.abs(linear.matrix - exact.matrix).max() <= 0.01 * scale, variant


def test_a_closed_pipe_and_an_isolated_junction_have_no_signature(tmp_path: Path) -> None:
    path = write(tmp_path, "closed", h_status="Closed")
    [linear] = linear_signature_sets(path, positions=[0.5])
    closed = linear.pipes.index("H")
    assert np.all(linear.matrix[closed] == 0.0)
    assert np.all(np.abs(np.delete(linear.matrix, closed, axis=0)).max(axis=1) > 0)


def test_linear_signatures_keep_the_shape_of_the_reference_burst() -> None:
    # the reference burst drops paper15's heads by metres: no longer linear, the shape close
    exact = cached_signature_sets(PAPER15, positions=[0.5], method="epanet")[0]
    [linear] = linear_signature_sets(PAPER15, positions=[0.5])
    cosine = _cosine(exact.matrix, linear.matrix)
    assert np.median(cosine) > 0.99 and cosine.min() > 0.95


def test_hybrid_signatures_are_exact_at_mid_pipe_and_near_it_along_the_pipe() -> None:
    positions = [0.1, 0.5, 0.9]
    exact = cached_signature_sets(NET3, positions=positions, method="epanet")
    linear = linear_signature_sets(NET3, positions=positions)
    hybrid = linear_signature_sets(NET3, positions=positions, method="hybrid", workers=1)
    assert all(s.params["method"] == "hybrid" for s in hybrid)
    # the EPANET runs shared among processes: the same numbers
    shared = linear_signature_sets(NET3, positions=positions, method="hybrid", workers=2)
    assert all(np.array_equal(a.matrix, b.matrix) for a, b in zip(hybrid, shared, strict=True))
    assert np.array_equal(hybrid[1].matrix, exact[1].matrix)  # the same EPANET runs
    heard = (np.linalg.norm(exact[1].matrix, axis=1) > 1e-3) & (
        np.linalg.norm(linear[1].matrix, axis=1) > 1e-3
    )
    assert heard.sum() > 100
    for k in (0, 2):  # 10 % from either end
        near = _cosine(exact[k].matrix[heard], hybrid[k].matrix[heard])
        far = _cosine(exact[k].matrix[heard], linear[k].matrix[heard])
        assert np.percentile(near, 5) > 0.99 and np.median(near) > 0.999
        assert np.percentile(near, 5) > np.percentile(far, 5) + 0.01


def _cosine(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.sum(a * b, axis=1) / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1))


def test_the_method_is_chosen_by_size_and_checked() -> None:
    assert signature_method("auto", EXACT_SIGNATURES_UP_TO) == "epanet"
    assert signature_method("auto", EXACT_SIGNATURES_UP_TO + 1) == "hybrid"
    assert signature_method("auto", HYBRID_SIGNATURES_UP_TO) == "hybrid"
    assert signature_method("auto", HYBRID_SIGNATURES_UP_TO + 1) == "linear"
    assert signature_method("epanet", 10**6) == "epanet"
    assert signature_method("linear", 1) == "linear"
    with pytest.raises(ConfigError, match="unknown signature method 'fast'"):
        signature_method("fast", 1)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="position"):
        linear_signature_sets(PAPER15, positions=[1.0])
    sets = cached_signature_sets(PAPER15, ["N4", "N7"], positions=[0.3, 0.7], method="linear")
    assert [s.params["position"] for s in sets] == [0.3, 0.7]
    assert all(s.meters == ("N4", "N7") and s.params["method"] == "linear" for s in sets)


def test_calibrate_records_the_linear_signatures() -> None:
    from burstloc.experiments.calibrate import calibrate

    config = calibrate(PAPER15, capture_intervals=[0.2], meters=["N4", "N7"], signatures="linear")
    assert config.provenance["signatures"] == "linear"
    assert all(s.params["method"] == "linear" for s in config.model.signature_sets)
    with pytest.raises(ConfigError, match="unknown signature method"):
        calibrate(PAPER15, capture_intervals=[0.2], signatures="fast")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="workers must be a positive integer, got 0"):
        calibrate(PAPER15, capture_intervals=[0.2], workers=0)


def test_evaluate_localizes_with_the_configurations_own_signatures() -> None:
    # before, evaluate --config recomputed the localization model from the network file (its
    # exact signatures) instead of reading the configuration's, as the monitor does
    from burstloc.experiments.calibrate import calibrate
    from burstloc.experiments.ranking import RankingSetup

    meters = ["N4", "N7", "5"]
    config = calibrate(PAPER15, capture_intervals=[0.2], meters=meters, signatures="linear")
    setup = RankingSetup.build(PAPER15, meters, [0.2], config)
    used = setup.localizers.signature.signature_sets
    assert [s.params["method"] for s in used] == ["linear"] * len(used)
    for mine, stored in zip(used, config.model.signature_sets, strict=True):
        assert np.array_equal(mine.matrix, stored.matrix)
