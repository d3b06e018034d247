"""burstloc.sim.scenarios.cache: content-addressed keys, atomic NPZ entries, the cache directory."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from burstloc.sim.scenarios import cache as cache_mod
from burstloc.sim.scenarios.cache import DiskCache, arrays_sha256, cache_key, default_cache_dir
from burstloc.sim.scenarios.scenario import BurstScenario
from burstloc.sim.transient.tsnet import simulate_burst


def _file(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_key_depends_on_parameters_file_bytes_and_versions(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    a = _file(tmp_path, "a.inp", "network A")
    base = cache_key("ns/1", {"pipe": "7", "position": 0.5}, [a])
    assert base == cache_key("ns/1", {"position": 0.5, "pipe": "7"}, [a])  # order-free
    assert base != cache_key("ns/1", {"pipe": "7", "position": 0.25}, [a])
    assert base != cache_key("ns/2", {"pipe": "7", "position": 0.5}, [a])
    # Same bytes under another name: same key. Other bytes: another key.
    copy = tmp_path / "copy.inp"
    shutil.copyfile(a, copy)
    assert base == cache_key("ns/1", {"pipe": "7", "position": 0.5}, [copy])
    a.write_text("network A, edited", encoding="utf-8")
    assert base != cache_key("ns/1", {"pipe": "7", "position": 0.5}, [a])
    a.write_text("network A", encoding="utf-8")
    assert base == cache_key("ns/1", {"pipe": "7", "position": 0.5}, [a])
    # Another TSNet version: another key.
    versions = dict(cache_mod.package_versions())
    monkeypatch.setattr(cache_mod, "package_versions", lambda: {**versions, "tsnet": "9.9"})
    assert base != cache_key("ns/1", {"pipe": "7", "position": 0.5}, [a])


def test_key_covers_every_scenario_parameter(paper15: Path) -> None:
    base = BurstScenario(paper15, "7")
    changes = {
        "pipe": "8",
        "position": 0.3,
        "burst_start": 5.0,
        "opening_time": 0.5,
        "burst_coeff": 0.02,
        "wave_speed": 1000.0,
        "duration": 100.0,
        "engine": "DD",
        "time_step": 0.05,
        "solver": "tsnet",
    }
    assert set(changes) == set(base.parameters())
    keys = {
        BurstScenario(**{**vars(base), name: value}).cache_key() for name, value in changes.items()
    }
    assert len(keys) == len(changes) and base.cache_key() not in keys
    # Integers and floats of the same value are the same scenario.
    assert BurstScenario(paper15, "7", burst_start=10).cache_key() == base.cache_key()


def test_put_get_round_trip(cache_dir: Path) -> None:
    store = DiskCache(cache_dir)
    key = "ab" + "0" * 62
    assert store.get(key) is None and key not in store
    arrays = {"x": np.arange(5.0), "names": np.asarray(["a", "b"]), "meta": np.asarray("{}")}
    path = store.put(key, arrays)
    assert path == store.path_for(key) and path.is_relative_to(cache_dir) and key in store
    got = store.get(key)
    assert got is not None and set(got) == set(arrays)
    for name, value in arrays.items():
        np.testing.assert_array_equal(got[name], value)


def test_unreadable_entry_is_a_miss(cache_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = DiskCache(cache_dir)
    key = "cd" + "1" * 62
    store.path_for(key).parent.mkdir(parents=True)
    store.path_for(key).write_bytes(b"PK\x03\x04 truncated")
    assert store.get(key) is None
    assert f"cache entry {store.path_for(key)} is corrupt (unreadable" in capsys.readouterr().err
    assert not store.path_for(key).exists()
    store.put(key, {"x": np.ones(2)})
    got = store.get(key)
    assert got is not None
    np.testing.assert_array_equal(got["x"], np.ones(2))


def test_default_directory_env_then_platformdirs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("BURSTLOC_CACHE_DIR", str(tmp_path / "env"))
    assert default_cache_dir() == tmp_path / "env"
    assert DiskCache().directory == tmp_path / "env"
    assert DiskCache(tmp_path / "arg").directory == tmp_path / "arg"
    monkeypatch.delenv("BURSTLOC_CACHE_DIR")
    monkeypatch.setattr(
        cache_mod.platformdirs, "user_cache_dir", lambda app: f"/home/u/.cache/{app}"
    )
    assert default_cache_dir() == Path("/home/u/.cache/burstloc")


def test_second_simulation_is_loaded_from_the_cache(tiny_network: Path, cache_dir: Path) -> None:
    scenario = BurstScenario(tiny_network, "B", burst_start=0.2, duration=1.5)
    store = DiskCache(cache_dir)
    first = simulate_burst(scenario, cache=store)
    assert first.metadata["cache"] == "miss"
    assert store.path_for(scenario.cache_key()).is_file()
    second = simulate_burst(scenario, cache=store)
    assert second.metadata["cache"] == "hit"
    np.testing.assert_array_equal(second.heads, first.heads)
    np.testing.assert_array_equal(second.time, first.time)
    assert second.junctions == first.junctions and second.time_step == first.time_step
    # Nothing else was written next to the entry (no temporaries left behind).
    files = [p for p in cache_dir.rglob("*") if p.is_file()]
    assert files == [store.path_for(scenario.cache_key())]


def test_cache_false_stores_nothing(
    tiny_network: Path, cache_dir: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("BURSTLOC_CACHE_DIR", str(cache_dir))
    simulate_burst(BurstScenario(tiny_network, "B", burst_start=0.2, duration=1.5), cache=False)
    assert not cache_dir.exists()


@pytest.mark.parametrize(
    ("damage", "reason"),
    [
        ("nan", "its checksum does not match"),
        ("nan-resummed", "array 'x' holds NaN or infinite values"),
        ("reshaped", "its checksum does not match"),
        ("no-checksum", "its checksum does not match"),
    ],
)
def test_a_corrupt_entry_is_reported_deleted_and_missed(
    cache_dir: Path, capsys: pytest.CaptureFixture[str], damage: str, reason: str
) -> None:
    store = DiskCache(cache_dir)
    key = "ef" + "2" * 62
    path = store.put(key, {"x": np.arange(6.0), "meta": np.asarray("{}")})
    with np.load(path, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    if damage.startswith("nan"):
        arrays["x"] = np.full(6, np.nan)
    if damage == "nan-resummed":  # a checksum that fits: the NaN itself is refused
        arrays[DiskCache.CHECKSUM] = np.asarray(
            arrays_sha256({k: v for k, v in arrays.items() if k != DiskCache.CHECKSUM})
        )
    if damage == "reshaped":
        arrays["x"] = arrays["x"].reshape(2, 3)
    if damage == "no-checksum":
        del arrays[DiskCache.CHECKSUM]
    np.savez(path, **arrays)
    assert store.get(key) is None
    err = capsys.readouterr().err
    assert f"burstloc: warning: cache entry {path} is corrupt ({reason}" in err
    assert "dropped, recomputing" in err and not path.exists()


def test_put_refuses_non_finite_values(cache_dir: Path) -> None:
    with pytest.raises(ValueError, match="array 'x' holds NaN"):
        DiskCache(cache_dir).put("ab" + "3" * 62, {"x": np.asarray([1.0, np.inf])})
