"""The stored localization model (burstloc.localize.model) and the localizers built from it."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from burstloc.constants import CLOCK_TOLERANCE, WAVE_SPEED_TOLERANCE
from burstloc.exceptions import ConfigError
from burstloc.localize.decide import RankingLocalizers
from burstloc.localize.evidence import BurstEvidence, MeterAlarm
from burstloc.localize.model import MODEL_FORMAT, LocalizationModel
from burstloc.localize.pipes import PipeGeometry
from burstloc.localize.signature import SignatureSet
from line_network import METERS, PIPES, WAVE, line_arrival, line_signature

MATRIX = np.array([[1.0, 1.0, 0.4, 0.2], [0.6, 1.0, 0.9, 0.4], [0.1, 0.3, 1.0, 1.0]])


def _sets(network_hash: str = "sha256:line", meters: tuple[str, ...] = METERS) -> tuple:
    return tuple(
        SignatureSet(
            network_hash=network_hash,
            meters=meters,
            pipes=PIPES,
            endpoints={f"p{i}{i + 1}": (f"m{i}", f"m{i + 1}") for i in range(3)},
            matrix=MATRIX[:, : len(meters)] * scale,
            baseline=np.full(len(meters), 50.0),
            params={"position": position},
        )
        for position, scale in ((0.25, 1.0), (0.75, 1.1))
    )


def _line_model(**changes: object) -> LocalizationModel:
    """The line network of line_network.py as a stored model (plus an unreachable node x)."""
    pos = {m: 600.0 * i for i, m in enumerate(METERS)}
    distances = {n: np.array([abs(pos[n] - pos[m]) for m in METERS]) for n in METERS}
    distances["x"] = np.full(len(METERS), math.inf)
    fields: dict[str, object] = {
        "network_hash": "sha256:line",
        "meters": METERS,
        "pipes": tuple(PipeGeometry(f"p{i}{i + 1}", f"m{i}", f"m{i + 1}", 600.0) for i in range(3)),
        "node_distances": distances,
        "signature_sets": _sets(),
        "wave_speed": WAVE,
    }
    fields.update(changes)
    return LocalizationModel(**fields)  # type: ignore[arg-type]


def _evidence() -> BurstEvidence:
    """A burst 150 m along p12 at t = 10 s: alarms as arrivals, and its lasting drop."""
    t = np.arange(0.0, 90.0, 0.5)
    arrive = [10.0 + abs(750.0 - 600.0 * i) / WAVE for i in range(len(METERS))]
    drop = 0.8 * MATRIX[1]
    readings = np.stack(
        [np.where(t < a, 50.0, 50.0 - d) for a, d in zip(arrive, drop, strict=True)], axis=1
    )
    alarms = {
        m: MeterAlarm(m, math.floor(a / 0.5) * 0.5, -float(d))
        for m, a, d in zip(METERS, arrive, drop, strict=True)
    }
    return BurstEvidence(METERS, t, readings, onset=10.0, capture_interval=0.5, alarms=alarms)


def test_json_round_trip_keeps_everything() -> None:
    model = _line_model()
    doc = json.loads(json.dumps(model.to_json(), allow_nan=False))  # strict JSON: no Infinity
    assert doc["format"] == MODEL_FORMAT
    assert doc["node_distances"]["x"] == [None] * len(METERS)
    back = LocalizationModel.from_json(doc)
    assert back == model
    assert np.all(np.isinf(back.node_distances["x"]))
    np.testing.assert_array_equal(back.node_distances["m1"], [600.0, 0.0, 600.0, 1200.0])
    assert [s.params["position"] for s in back.signature_sets] == [0.25, 0.75]
    assert back != _line_model(wave_speed=1000.0)


def test_localizers_from_the_model_rank_as_the_directly_built_ones() -> None:
    evidence = _evidence()
    stored = LocalizationModel.from_json(json.loads(json.dumps(_line_model().to_json())))
    built = RankingLocalizers.from_model(stored)
    direct_arrival = line_arrival()
    assert built.arrival.rank(evidence).scores() == direct_arrival.rank(evidence).scores()
    assert built.arrival.pipe_travel == direct_arrival.pipe_travel
    direct_signature = line_signature(MATRIX)
    assert [s.params["position"] for s in built.signature.signature_sets] == [0.25, 0.75]
    ranking = built.fused.rank(evidence)
    assert ranking.best is not None and ranking.best.pipe == "p12"
    assert built.signature.rank(evidence).best.pipe == direct_signature.rank(evidence).best.pipe  # type: ignore[union-attr]


def test_the_model_refuses_another_network_or_other_meters_by_name() -> None:
    model = _line_model()
    model.check("sha256:line", METERS)
    with pytest.raises(ConfigError, match="model is for network sha256:line, not sha256:other"):
        model.check("sha256:other", METERS)
    with pytest.raises(ConfigError, match=r"model is for meters \['m0', 'm1', 'm2', 'm3'\], not"):
        model.check("sha256:line", ("m1", "m0", "m2", "m3"))


def test_parts_that_do_not_fit_are_refused() -> None:
    with pytest.raises(ConfigError, match="no distances from node 'm3'"):
        _line_model(node_distances={"m0": np.zeros(4), "m1": np.zeros(4), "m2": np.zeros(4)})
    with pytest.raises(ConfigError, match=r"node_distances\.m0 must be 4 lengths"):
        _line_model(node_distances={n: np.zeros(3) for n in METERS})
    with pytest.raises(ConfigError, match="another network or other meters"):
        _line_model(signature_sets=_sets(network_hash="sha256:other"))
    with pytest.raises(ConfigError, match="another network or other meters"):
        _line_model(signature_sets=_sets(meters=METERS[:3]))
    with pytest.raises(ConfigError, match="at least one signature set"):
        _line_model(signature_sets=())
    with pytest.raises(ConfigError, match="pipes must hold 1 to"):
        _line_model(pipes=())
    with pytest.raises(ConfigError, match="wave_speed"):
        _line_model(wave_speed=0.0)
    with pytest.raises(ConfigError, match=r"wave_speed must be a finite number in \(0, 10000\]"):
        _line_model(wave_speed=1e300)
    with pytest.raises(ConfigError, match="meters lists 'm0' more than once"):
        _line_model(meters=("m0", "m0", "m2", "m3"))


def test_malformed_documents_are_config_errors() -> None:
    doc = _line_model().to_json()
    with pytest.raises(ConfigError, match="not a burstloc localization model"):
        LocalizationModel.from_json({**doc, "format": "burstloc-localization-model/0"})
    with pytest.raises(ConfigError, match="malformed localization model"):
        LocalizationModel.from_json({k: v for k, v in doc.items() if k != "node_distances"})
    broken = json.loads(json.dumps(doc))
    broken["signature_sets"][0]["matrix"] = [[1.0]]
    with pytest.raises(ConfigError, match="malformed localization model"):
        LocalizationModel.from_json(broken)


def _fronts(scale: float = 1.0) -> dict[str, np.ndarray]:
    return {f"p{i}{i + 1}": scale * np.array([1.0, 0.5, 0.25, 0.125]) for i in range(3)}


def test_wave_fronts_round_trip_and_reach_the_arrival_localizer() -> None:
    model = _line_model(fronts=_fronts())
    doc = json.loads(json.dumps(model.to_json(), allow_nan=False))
    assert doc["fronts"]["p01"] == [1.0, 0.5, 0.25, 0.125]
    back = LocalizationModel.from_json(doc)
    assert back == model and back != _line_model(fronts=_fronts(2.0))
    assert back.fronts is not None
    np.testing.assert_array_equal(back.fronts["p12"], _fronts()["p12"])
    arrival = RankingLocalizers.from_model(back).arrival
    np.testing.assert_array_equal(arrival._fronts, np.stack(list(_fronts().values())))  # type: ignore[arg-type]
    # a model stored without them loads, and every silent meter counts as before
    older = LocalizationModel.from_json({k: v for k, v in doc.items() if k != "fronts"})
    assert older.fronts is None and "fronts" not in older.to_json()
    assert RankingLocalizers.from_model(older).arrival._fronts is None


def test_wave_fronts_that_do_not_fit_are_refused() -> None:
    with pytest.raises(ConfigError, match=r"fronts must have one row per pipe \(missing \['p23'\]"):
        _line_model(fronts={k: v for k, v in _fronts().items() if k != "p23"})
    with pytest.raises(ConfigError, match=r"fronts\.p01 must be 4 finite values >= 0"):
        _line_model(fronts={**_fronts(), "p01": np.array([1.0, -0.5, 0.0, 0.0])})
    with pytest.raises(ConfigError, match=r"fronts\.p12 must be 4 finite values"):
        _line_model(fronts={**_fronts(), "p12": np.ones(3)})
    doc = _line_model(fronts=_fronts()).to_json()
    with pytest.raises(ConfigError, match="malformed localization model"):
        LocalizationModel.from_json({**doc, "fronts": [1, 2]})


def test_the_timing_tolerances_are_stored_checked_and_reach_the_arrival_localizer() -> None:
    model = _line_model(wave_speed_tolerance=0.12, clock_tolerance=0.004)
    doc = json.loads(json.dumps(model.to_json()))
    assert doc["wave_speed_tolerance"] == 0.12 and doc["clock_tolerance_s"] == 0.004
    back = LocalizationModel.from_json(doc)
    assert back == model and back != _line_model()
    arrival = RankingLocalizers.from_model(back).arrival
    assert (arrival.wave_speed_tolerance, arrival.clock_tolerance) == (0.12, 0.004)
    # a model stored before they were recorded gets the defaults
    del doc["wave_speed_tolerance"], doc["clock_tolerance_s"]
    older = LocalizationModel.from_json(doc)
    assert older.wave_speed_tolerance == WAVE_SPEED_TOLERANCE
    assert older.clock_tolerance == CLOCK_TOLERANCE
    for field, value in (("wave_speed_tolerance", -0.1), ("wave_speed_tolerance", 1.5)):
        with pytest.raises(ConfigError, match=field):
            _line_model(**{field: value})
    with pytest.raises(ConfigError, match="clock_tolerance"):
        _line_model(clock_tolerance=math.nan)


def test_connectors_are_stored_checked_and_reach_the_arrival_localizer() -> None:
    model = _line_model(connectors=[("m3", "x", 0.0)])
    doc = json.loads(json.dumps(model.to_json()))
    assert doc["connectors"] == [["m3", "x", 0.0]]
    back = LocalizationModel.from_json(doc)
    assert back == model and back != _line_model()
    assert RankingLocalizers.from_model(back).arrival.connectors == (("m3", "x", 0.0),)
    del doc["connectors"]  # a model stored before they were: the pipes alone
    older = LocalizationModel.from_json(doc)
    assert older.connectors is None
    assert RankingLocalizers.from_model(older).arrival.connectors == ()
    with pytest.raises(ConfigError, match=r"connectors\[0\] must be \[start node, end node"):
        _line_model(connectors=[("m3", 5, 0.0)])
    with pytest.raises(ConfigError, match=r"connectors\[1\]\.length"):
        _line_model(connectors=[("m3", "x", 0.0), ("m0", "x", -1.0)])
    broken = {**model.to_json(), "connectors": [["m3", "x"]]}
    with pytest.raises(ConfigError, match=r"connectors\[0\]"):
        LocalizationModel.from_json(broken)


def test_a_model_restricted_to_fewer_meters_keeps_the_rest_as_it_was() -> None:
    """The subset localizers (a meter silent) read the same timing factor, tolerances and
    connectors as the whole model's."""
    from burstloc.live.subset import restricted_model

    model = _line_model(
        connectors=[("m3", "x", 0.0)], timing_factor=2.5, wave_speed_tolerance=0.12,
        clock_offsets={"m1": 0.01, "m2": -0.02},
    )  # fmt: skip
    fewer = restricted_model(model, ("m0", "m2", "m3"))
    assert fewer.meters == ("m0", "m2", "m3")
    assert fewer.timing_factor == 2.5 and fewer.wave_speed_tolerance == 0.12
    assert fewer.connectors == model.connectors and fewer.clock_offsets == {"m2": -0.02}
    np.testing.assert_array_equal(fewer.node_distances["m1"], [600.0, 600.0, 1200.0])


def test_the_meters_taking_part_are_the_columns_and_alarms_of_those_not_excluded() -> None:
    """A meter excluded (silent): its column and alarms leave, the others' alarms are
    re-indexed to the columns that stay, and the subset's own localizers rank them."""
    from burstloc.live.subset import SubsetLocalizers, taking_part
    from burstloc.localize.evidence import IndexedAlarm

    model = _line_model()
    whole = RankingLocalizers.from_model(model)
    subsets = SubsetLocalizers(model)
    readings = np.arange(20.0).reshape(5, 4)
    alarms = [IndexedAlarm(3, 4, 2, -0.5), IndexedAlarm(1, 3, 1, -0.4), IndexedAlarm(0, 4, 3, -0.2)]
    got, moved, meters, localizers = taking_part(METERS, {"m1"}, whole, subsets, readings, alarms)
    assert meters == ("m0", "m2", "m3")
    np.testing.assert_array_equal(got, readings[:, [0, 2, 3]])
    assert moved == [IndexedAlarm(2, 4, 2, -0.5), IndexedAlarm(0, 4, 3, -0.2)]
    assert localizers is subsets.get(("m0", "m2", "m3"))
    assert localizers["arrival"].meters == ("m0", "m2", "m3")
    # every meter reporting, or no subsets to build from: all of them, as they are
    for excluded, built in (set(), subsets), ({"m1"}, None):
        got, moved, meters, localizers = taking_part(
            METERS, excluded, whole, built, readings, alarms
        )
        assert meters == METERS and got is readings and moved == alarms and localizers is whole
