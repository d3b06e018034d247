"""The stored configuration (burstloc.localize.config): save, load, refuse by name, and the
localization model it carries."""

from __future__ import annotations

import dataclasses
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from burstloc import _core
from burstloc.exceptions import ConfigError
from burstloc.experiments.calibrate import calibrate
from burstloc.localize.config import CALIBRATION_FORMAT, Calibration
from burstloc.localize.interval import calibrated_bank


@pytest.fixture(scope="module")
def stored(tiny: Path) -> Calibration:
    return calibrate(tiny, capture_intervals=[0.2], noise_sigma=0.01, max_samples=300_000)


def test_save_load_and_refuse_other_network(tiny_network: Path, tmp_path: Path) -> None:
    config = calibrate(
        tiny_network, capture_intervals=[0.2, 5.0], noise_sigma=0.01, max_samples=300_000, name="t"
    )
    assert config.meters == ("J1", "J2", "J3", "J4")
    fine, coarse = config.for_interval(0.2), config.for_interval(5.0)
    assert fine.cusum_threshold["J2"] > coarse.cusum_threshold["J2"]  # more readings per hour
    assert fine.uniform("cusum") == {"threshold": fine.cusum_threshold["J1"], "drift": 0.01}
    assert coarse.localization_interval == 10
    path = config.save(tmp_path / "t.json")
    assert json.loads(path.read_text())["name"] == "t"
    back = Calibration.load(path, network=tiny_network, meters=config.meters)
    assert back == config
    with pytest.raises(ConfigError, match="10 s capture"):
        back.for_interval(10.0)
    other = tmp_path / "other.inp"
    other.write_text(tiny_network.read_text().replace("J4   0      2", "J4   0      3"))
    with pytest.raises(ConfigError, match="'t' was calibrated for network"):
        Calibration.load(path, network=other)
    with pytest.raises(ConfigError, match=r"other meters \(1 missing \['J4'\]\)"):
        back.check(tiny_network, ["J1", "J2", "J3"])
    many = [f"X{i}" for i in range(9)]
    with pytest.raises(ConfigError) as refused:
        back.check(tiny_network, ["J1", "J2", "J3", "J4", *many])
    assert "(9 extra ['X0', 'X1', 'X2', 'X3', 'X4'] and 4 more)" in str(refused.value)
    assert "X5" not in str(refused.value)
    with pytest.raises(ConfigError, match="the same meters in another order"):
        back.check(tiny_network, ["J4", "J3", "J2", "J1"])
    path.write_text('{"format": "nope"}')
    with pytest.raises(ConfigError, match="not a burstloc configuration"):
        Calibration.load(path)


def test_the_model_travels_with_the_configuration(
    tiny: Path, stored: Calibration, tmp_path: Path
) -> None:
    path = stored.save(tmp_path / "c.json")
    doc = json.loads(path.read_text())
    assert doc["format"] == CALIBRATION_FORMAT
    assert doc["model"]["format"] == "burstloc-localization-model/1"
    assert doc["model"]["network_hash"] == doc["network_hash"]
    back = Calibration.load(path, network=tiny)
    assert back.model == stored.model
    # a model for other meters than the configuration's is refused by name
    doc["meters"] = ["J1", "J2", "J3"]
    path.write_text(json.dumps(doc))
    with pytest.raises(
        ConfigError,
        match=r"model is for meters \['J1', 'J2', 'J3', 'J4'\], not \['J1', 'J2', 'J3'\]",
    ):
        Calibration.load(path)
    # and one for another network
    doc = stored.to_json()
    doc["model"]["network_hash"] = "sha256:0"
    for sig in doc["model"]["signature_sets"]:
        sig["network_hash"] = "sha256:0"
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match="model is for network sha256:0"):
        Calibration.load(path)
    # a damaged model is a malformed configuration
    doc = stored.to_json()
    del doc["model"]["pipes"]
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match="malformed localization model"):
        Calibration.load(path)


def test_a_configuration_of_the_previous_format_asks_to_recalibrate(
    stored: Calibration, tmp_path: Path
) -> None:
    doc = stored.to_json()
    del doc["model"]
    doc["format"] = "burstloc-calibration/1"
    path = tmp_path / "old.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(
        ConfigError,
        match=r"earlier burstloc .*holds no localization model; "
        r"re-run `burstloc calibrate .*tiny\.inp --out PATH`",
    ):
        Calibration.load(path)
    doc["format"] = CALIBRATION_FORMAT  # the current format without a model is malformed
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=r"old\.json: field model is missing"):
        Calibration.load(path)


def test_calibrated_bank_uses_the_interval_settings(stored: Calibration) -> None:
    cal = stored.for_interval(0.2)
    readings = np.full((400, 4), 50.0)
    readings[200:, 2] -= 0.5  # a step on the third meter
    cusum = _core.DetectorBank("cusum", 4, **cal.uniform("cusum"))
    shewhart = _core.DetectorBank(
        "shewhart", 4, **cal.uniform("shewhart"), window=2 * cal.localization_interval
    )
    for kind, reference in (("cusum", cusum), ("shewhart", shewhart)):
        bank = calibrated_bank(kind, 4, cal)
        assert (bank.kind, bank.channels) == (kind, 4)
        alarms = [(a.channel, a.index) for a in bank.run(readings)]
        assert alarms and alarms == [(a.channel, a.index) for a in reference.run(readings)]
        assert {channel for channel, _ in alarms} == {2}
    with pytest.raises(ConfigError, match="unknown detector"):
        calibrated_bank("ewma", 4, cal)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda d: d["intervals"][0].update(localization_interval=10**12),
            r"intervals\[0\]\.localization_interval must be an integer in \[1, 100000\], "
            r"got 1000000000000",
        ),
        (
            lambda d: d["intervals"][0].update(decision_delay_s=-1.0),
            r"intervals\[0\]\.decision_delay_s must be a finite number in \[0, 86400\]",
        ),
        (
            lambda d: d["intervals"][0]["shewhart"]["threshold"].pop("J2"),
            r"intervals\[0\]\.shewhart\.threshold must have one value per meter "
            r"\(missing \['J2'\]",
        ),
        (
            lambda d: d["intervals"].append(dict(d["intervals"][0])),
            r"intervals\[1\]\.capture_interval lists 0\.2 s a second time",
        ),
        (lambda d: d.update(intervals=[]), r"field intervals must be a list of 1 to 64"),
        (lambda d: d.update(network_hash="sha256:xyz"), r"network_hash must be 'sha256:'"),
        (lambda d: d.update(false_alarm_rate_per_hour=0), r"false_alarm_rate_per_hour must be"),
        (lambda d: d["noise_sigma"].update(J1=-0.1), r"noise_sigma\.J1 must be a finite"),
        (lambda d: d.update(provenance=[1]), r"field provenance must be a JSON object"),
        (lambda d: d["model"].update(wave_speed="fast"), r"model: malformed localization model"),
    ],
)
def test_every_field_is_checked_on_load_naming_file_and_field(
    stored: Calibration, tmp_path: Path, edit, message: str
) -> None:  # type: ignore[no-untyped-def]
    doc = stored.to_json()
    edit(doc)
    path = tmp_path / "c.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=rf"^configuration {re.escape(str(path))}: .*{message}"):
        Calibration.load(path)


def test_a_configuration_built_in_code_is_checked_too(stored: Calibration) -> None:
    item = stored.intervals[0]
    with pytest.raises(
        ConfigError, match=r"^capture_interval must be a finite number in \(0, 3600\]"
    ):
        dataclasses.replace(item, capture_interval=math.inf)
    with pytest.raises(ConfigError, match=r"^cusum\.drift\.J1 must be a number, got null"):
        dataclasses.replace(item, cusum_drift={**item.cusum_drift, "J1": None})
    with pytest.raises(ConfigError, match=r"^meters lists 'J1' more than once"):
        dataclasses.replace(stored, meters=("J1", "J1", "J2", "J3"))


def test_a_configuration_saved_as_npz_loads_the_same(
    tiny: Path, stored: Calibration, tmp_path: Path
) -> None:
    from burstloc._atomic import write_json_npz
    from burstloc._validate import read_json_npz

    path = stored.save(tmp_path / "c.npz")
    assert Calibration.load(path, network=tiny) == stored
    # the tiny network's matrices are below the size that goes binary: force it, and check
    # that the signature matrices really left the JSON text and come back bit for bit
    write_json_npz(tmp_path / "small.npz", stored.to_json(), min_size=4)
    with np.load(tmp_path / "small.npz") as data:
        assert len(data.files) > len(stored.model.signature_sets)  # the document and arrays
        text = data["document"].tobytes().decode()
    assert '"matrix":{"$npz":' in text
    back = Calibration.from_json(read_json_npz(tmp_path / "small.npz", "configuration"), "c")
    assert back == stored
    assert back.model.signature_sets[0].matrix.tobytes() == (
        stored.model.signature_sets[0].matrix.tobytes()
    )
