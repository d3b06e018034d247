"""Burst signatures from the hydraulic model (offline: WNTR/EPANET steady states, cached)."""

from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest

from burstloc.exceptions import ConfigError, NetworkError
from burstloc.inp import network_hash
from burstloc.localize.signature import SignatureSet, rank_drop
from burstloc.network import load_network, split_pipe
from burstloc.sim.signatures.compute import (
    DEFAULT_BURST_COEFF,
    cached_signature_sets,
    cached_signatures,
    compute_signatures,
)


def _heads_with_burst(network: Path, pipe: str, fraction: float, coeff: float) -> dict[str, float]:
    """Steady heads with an emitter ``coeff`` at ``fraction`` along ``pipe`` (an 'observation')."""
    import wntr

    wn = load_network(network)
    wn.options.hydraulic.demand_model = "PDD"
    split = split_pipe(wn, pipe, fraction)
    split.network.get_node(split.burst_node).emitter_coefficient = coeff
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = wntr.sim.EpanetSimulator(split.network).run_sim(file_prefix=os.path.join(tmp, "x"))
    heads = res.node["head"].iloc[0]
    return {n: float(heads[n]) for n in wn.junction_name_list}


def test_computed_signatures_on_tiny_network(tiny_network: Path) -> None:
    sig = compute_signatures(tiny_network)
    assert set(sig.pipes) == {"A", "B", "C", "D", "E"}
    assert sig.meters == ("J1", "J2", "J3", "J4")
    # every burst lowers every head; a burst on the supply pipe A lowers them all about equally
    assert np.all(sig.matrix > 0)
    a = sig.matrix[sig.pipes.index("A")]
    assert np.ptp(a) < 0.2 * a.mean()
    # a burst on the dead-end pipe E hurts J4 (its end) most
    e = sig.matrix[sig.pipes.index("E")]
    assert int(np.argmax(e)) == sig.meters.index("J4")
    # end nodes follow the steady flow: everything flows away from the reservoir
    assert sig.endpoints["A"] == ("R1", "J1")
    assert sig.endpoints["E"] == ("J3", "J4")
    assert sig.network_hash == network_hash(tiny_network)


@pytest.mark.parametrize(("pipe", "fraction", "coeff"), [("B", 0.5, 0.004), ("E", 0.3, 0.002)])
def test_true_pipe_ranks_first_for_a_model_burst(
    tiny_network: Path, pipe: str, fraction: float, coeff: float
) -> None:
    sig = compute_signatures(tiny_network)
    after = _heads_with_burst(tiny_network, pipe, fraction, coeff)
    drop = sig.baseline - np.array([after[m] for m in sig.meters])
    ranking = rank_drop(drop, sig)
    assert ranking.best is not None and ranking.best.pipe == pipe


def test_compute_signatures_rejects_bad_input(tiny_network: Path) -> None:
    with pytest.raises(NetworkError, match="R1"):
        compute_signatures(tiny_network, meters=["R1"])
    with pytest.raises(ConfigError):
        compute_signatures(tiny_network, burst_coeff=0.0)
    with pytest.raises(ConfigError):
        compute_signatures(tiny_network, position=1.0)


def test_cached_signatures_are_computed_once(
    tiny_network: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    first = cached_signatures(tiny_network, ["J4", "J2"], cache_dir=tmp_path)
    assert first.meters == ("J4", "J2")
    files = list(tmp_path.glob("*.npz"))
    assert len(files) == 1

    def boom(*args: object, **kwargs: object) -> SignatureSet:
        raise AssertionError("recomputed although cached")

    monkeypatch.setattr("burstloc.sim.signatures.compute.compute_signatures", boom)
    again = cached_signatures(tiny_network, ["J4", "J2"], cache_dir=tmp_path)
    np.testing.assert_array_equal(again.matrix, first.matrix)
    # another network file is another entry (and here: computed, hence the error)
    other = tmp_path / "other.inp"
    other.write_text(tiny_network.read_text().replace("R1   60", "R1   61"))
    with pytest.raises(AssertionError, match="recomputed"):
        cached_signatures(other, cache_dir=tmp_path)


def test_positions_along_the_pipe_match_an_off_centre_burst(
    tiny_network: Path, tmp_path: Path
) -> None:
    sets = cached_signature_sets(tiny_network, cache_dir=tmp_path)
    assert [s.params["position"] for s in sets] == [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]
    assert len(list(tmp_path.glob("*.npz"))) == len(sets)
    middle = sets[4]
    for pipe in middle.pipes:
        for fraction in (0.1, 0.9):
            after = _heads_with_burst(tiny_network, pipe, fraction, DEFAULT_BURST_COEFF)
            drop = middle.baseline - np.array([after[m] for m in middle.meters])
            ranking = rank_drop(drop, sets)
            # the reference burst at a candidate position is matched (to EPANET's precision)
            assert ranking.best is not None and ranking.best.pipe == pipe
            assert -ranking.best.score < 1e-3
            # the mid-point signature alone fits it worse
            mid_only = {p.pipe: p.score for p in rank_drop(drop, middle)}
            assert mid_only[pipe] < ranking.best.score
            # each pipe scores its best position
            singles = [{p.pipe: p.score for p in rank_drop(drop, s)} for s in sets]
            for ranked in ranking:
                assert ranked.score == max(single[ranked.pipe] for single in singles)


def test_signature_sets_need_a_position() -> None:
    with pytest.raises(ConfigError, match="at least one"):
        cached_signature_sets("x.inp", positions=())
