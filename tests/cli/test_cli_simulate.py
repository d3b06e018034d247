"""`burstloc simulate`: scenario files, capture intervals, bad input and exit codes."""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from burstloc.cli import main
from connector_network import CONNECTOR_INP

SHORT = ["--burst-start", "0.2", "--duration", "1.5", "--quiet", "--workers", "1"]


def _run(*args: str | Path) -> int:
    return main([str(a) for a in args])


def test_all_pipes_one_file_each(tiny_network: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    assert (
        _run("simulate", tiny_network, "--all", "--out", out, "--cache-dir", tmp_path / "c", *SHORT)
        == 0
    )
    files = sorted(p.name for p in out.iterdir())
    assert files == [f"tiny_pipe-{p}.npz" for p in "ABCDE"]
    with np.load(out / "tiny_pipe-C.npz", allow_pickle=False) as data:
        time, heads, junctions = data["time"], data["heads"], list(data["junctions"])
        meta = json.loads(str(data["metadata"]))
    assert junctions == ["J1", "J2", "J3", "J4"] and heads.shape == (time.size, 4)
    assert meta["pipe"] == "C" and (meta["true_start"], meta["true_end"]) == ("J1", "J3")
    assert meta["duration"] == 1.5 and meta["burst_start"] == 0.2
    np.testing.assert_allclose(np.diff(time), meta["time_step"])


def test_chosen_pipes_parameters_and_capture_interval(tiny_network: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    code = _run(
        "simulate", tiny_network, "--pipe", "B", "E", "--position", "0.25", "--burst-coeff", "0.02",
        "--opening-time", "0", "--wave-speed", "1000", "--capture-interval", "0.1",
        "--capture-phase", "0.05", "--out", out, "--no-cache", *SHORT,
    )  # fmt: skip
    assert code == 0
    assert sorted(p.name for p in out.iterdir()) == ["tiny_pipe-B.npz", "tiny_pipe-E.npz"]
    with np.load(out / "tiny_pipe-B.npz", allow_pickle=False) as data:
        meta = json.loads(str(data["metadata"]))
        np.testing.assert_allclose(np.diff(data["time"]), 0.1)
        assert data["time"][0] == pytest.approx(0.05)
    assert meta["position"] == 0.25 and meta["burst_coeff"] == 0.02
    assert meta["opening_time"] == 0.0 and meta["wave_speed"] == 1000.0
    assert meta["capture_interval"] == 0.1 and meta["capture_phase"] == 0.05


def test_min_pipe_length_simulates_the_transient_ready_model(tmp_path: Path) -> None:
    network = tmp_path / "connectors.inp"
    network.write_text(CONNECTOR_INP)
    out = tmp_path / "out"
    code = _run(
        "simulate", network, "--pipe", "C1", "--min-pipe-length", "6", "--burst-start", "0.05",
        "--duration", "0.3", "--out", out, "--no-cache", "--quiet", "--workers", "1",
    )  # fmt: skip
    assert code == 0
    with np.load(out / "connectors_pipe-C1.npz", allow_pickle=False) as data:
        meta = json.loads(str(data["metadata"]))
        assert list(data["junctions"]) == ["J1", "J2", "J3", "J4", "J5", "J6"]
    assert meta["pipe"] == "C1" and meta["min_pipe_length"] == 6.0
    assert meta["transient_model"]["lengthened"] == {"C1": 0.3, "C2": 0.5}
    # the burst splits the lengthened 6 m connector in two 3 m halves: the step follows them
    assert meta["time_step"] == pytest.approx(3.0 / 2400, rel=0.05)


def test_wave_speeds_reach_the_burst_and_the_event_simulations(tmp_path: Path) -> None:
    network = tmp_path / "connectors.inp"
    network.write_text(CONNECTOR_INP)
    speeds = tmp_path / "speeds.json"
    speeds.write_text(
        '{"pipes": {"P5": 900}, "diameters": [{"up_to_mm": 1000, "wave_speed": 600}]}'
    )
    out = tmp_path / "out"
    common = ["--burst-start", "0.05", "--duration", "0.3", "--out", out, "--no-cache", "--quiet"]
    common += ["--workers", "1", "--wave-speeds", speeds]
    assert _run("simulate", network, "--pipe", "C1", "--min-pipe-length", "6", *common) == 0
    event = ["--event", "demand-step", "--asset", "J3", "--demand-change", "0.001"]
    assert _run("simulate", network, *event, *common) == 0
    recorded = {"pipes": {"P5": 900.0}, "diameters": [{"up_to_mm": 1000.0, "wave_speed": 600.0}]}
    for path in out.iterdir():
        with np.load(path, allow_pickle=False) as data:
            assert json.loads(str(data["metadata"]))["wave_speeds"] == recorded, path.name
    # C1's 3 m halves at 600 m/s, not 1200 (3 / 2400 s): a step twice as long
    with np.load(out / "connectors_pipe-C1.npz", allow_pickle=False) as data:
        assert json.loads(str(data["metadata"]))["time_step"] == pytest.approx(3.0 / 1200, rel=0.05)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--pipe", "B", "Q"], "['Q']"),
        (
            ["--pipe", "B", "--position", "1.5"],
            "position must be strictly between 0 and 1, got 1.5",
        ),
        (["--pipe", "B", "--position", "0"], "got 0.0"),
        (["--pipe", "B", "--burst-start", "2", "--duration", "2"], "duration (2.0 s)"),
        (
            ["--pipe", "B", "--burst-coeff", "-1"],
            "--burst-coeff must be a positive number, got -1.0",
        ),
        (["--pipe", "B", "--wave-speed", "0"], "wave_speed must be > 0 m/s, got 0.0"),
        (["--pipe", "B", "--workers", "0"], "workers must be a positive integer, got 0"),
        (["--pipe", "B", "--min-pipe-length", "0"], "min_pipe_length must be > 0 m, got 0.0"),
        (["--pipe", "B", "--wave-speeds", "nowhere.csv"], "cannot read wave speeds nowhere.csv"),
        (
            ["--event", "demand-step", "--asset", "J1", "--min-pipe-length", "5"],
            "--min-pipe-length applies to bursts only",
        ),
        (
            ["--event", "demand-step", "--asset", "J1", "--burst-flow", "5"],
            "--burst-flow applies to bursts only",
        ),
    ],
)
def test_bad_input_exits_2_naming_the_value(
    tiny_network: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    words: str,
) -> None:
    assert (
        _run("simulate", tiny_network, *args, "--out", tmp_path / "o", "--no-cache", "--quiet") == 2
    )
    err = capsys.readouterr().err
    assert err.startswith("burstloc: error: ") and words in err
    assert not (tmp_path / "o").exists()


def test_missing_and_malformed_networks(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    assert _run("simulate", tmp_path / "none.inp", "--all", "--quiet", "--out", out) == 2
    assert "none.inp" in capsys.readouterr().err
    bad = tmp_path / "bad.inp"
    bad.write_text("[PIPES]\n A R1 J1 100\n", encoding="utf-8")
    assert _run("simulate", bad, "--all", "--quiet", "--out", out) == 2
    assert f"{bad}:2:" in capsys.readouterr().err
    assert not out.exists()


def test_a_failing_scenario_exits_1_after_writing_the_others(
    tiny_network: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # The largest stable time step differs per split pipe: 0.06 s is fine when A (300 m) is
    # split but too coarse when D (150 m) is.
    out = tmp_path / "out"
    code = _run(
        "simulate", tiny_network, "--pipe", "A", "D", "--time-step", "0.06", "--out", out,
        "--no-cache", "--burst-start", "0.2", "--duration", "1.5", "--quiet", "--workers", "1",
    )  # fmt: skip
    assert code == 1
    captured = capsys.readouterr()
    assert sorted(p.name for p in out.iterdir()) == ["tiny_pipe-A.npz"]
    assert "pipe D" in captured.err and "stability limit" in captured.err
    assert "wrote 1 scenario file(s)" in captured.out


def test_pipe_and_all_are_exclusive_and_one_is_required(tiny_network: Path) -> None:
    for args in (["--pipe", "A", "--all"], []):
        with pytest.raises(SystemExit) as info:
            _run("simulate", tiny_network, *args)
        assert info.value.code == 2


def test_command_line_process(tiny_network: Path, tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "burstloc.cli", "simulate", str(tiny_network), "--pipe", "Nope"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 2
    assert "unknown pipe(s) ['Nope']" in done.stderr and done.stdout == ""


def _small_file_limit() -> None:
    """In the child: files may not grow past 8 KiB, and a write past it fails (EFBIG) instead of
    killing the process (SIGXFSZ ignored), as a full disk fails a write with ENOSPC."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (8192, 8192))


def test_a_failed_write_prints_one_error_and_no_traceback(
    tiny_network: Path, tmp_path: Path
) -> None:
    """A scenario file of ~12 KB whose write the OS refuses midway: the clear error and exit 2,
    nothing after it (no "Exception ignored" from an archive left open)."""
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "burstloc.cli", "simulate", str(tiny_network), "--pipe", "A",
         "--out", str(out), "--no-cache", "--burst-start", "0.2", "--duration", "10", "--quiet",
         "--workers", "1"],
        capture_output=True, text=True, check=False, preexec_fn=_small_file_limit,
        env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert done.stderr.splitlines() == [
        f"burstloc: error: cannot write {out / 'tiny_pipe-A.npz'}: File too large"
    ]
    assert list(out.iterdir()) == []


def _monitor(network: Path, config: Path, feed: Path) -> subprocess.CompletedProcess[str]:
    argv = [sys.executable, "-m", "burstloc", "monitor", str(network), "--config", str(config)]
    argv += ["--capture-interval", "0.2", "--readings", str(feed), "--health-every", "0"]
    return subprocess.run(argv, capture_output=True, text=True, check=False)


@pytest.fixture(scope="module")
def paper15_config(paper15: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    from burstloc.experiments.calibrate import calibrate

    config = calibrate(paper15, capture_intervals=(0.2,))
    return config.save(tmp_path_factory.mktemp("cfg") / "paper15.json")


@pytest.mark.parametrize("start", [None, "2026-11-26T12:00:00+02:00"])
def test_a_feed_from_a_simulation_is_what_the_monitor_reads(
    start: str | None, paper15: Path, paper15_config: Path, tmp_path: Path
) -> None:
    # Before, nothing wrote a feed: `burstloc monitor --readings feed.csv` had no feed.
    feed = tmp_path / "feed.csv"
    args = ["simulate", paper15, "--pipe", "P7", "--duration", "14", "--capture-interval", "0.2"]
    args += ["--noise", "0.01", "--seed", "3", "--out", tmp_path / "out", "--quiet"]
    args += ["--start", start] if start else []
    assert _run(*args, "--feed", feed) == 0
    lines = feed.read_text().splitlines()
    assert lines[0] == "timestamp,meter,value" and len(lines) == 1 + 15 * 70
    first = [line.split(",") for line in lines[1:16]]
    assert [meter for _, meter, _ in first][:3] == ["N2", "N3", "N4"]
    assert {t for t, _, _ in first} == {start.replace("+", ".000+") if start else "0"}
    done = _monitor(paper15, paper15_config, feed)
    assert done.returncode == 0, done.stderr
    (decision,) = [json.loads(line) for line in done.stdout.splitlines()]
    assert decision["type"] == "decision" and decision["pipes"][0]["pipe"] == "P7"
    if start is None:  # times without float noise (was 10.600000000000001)
        assert decision["first_alarm"] == 10.6 and decision["pipes"][0]["score"] == 0.0
    again = tmp_path / "again.csv"
    assert _run(*args, "--feed", again) == 0
    assert again.read_text() == feed.read_text()  # seeded: the same noise


@pytest.mark.parametrize(
    ("extra", "says"),
    [
        (["--feed", "f.csv"], "--feed needs --capture-interval"),
        (["--feed", "f.csv", "--capture-interval", "0.2", "--all"], "one --pipe"),
        (["--noise", "0.01"], "--noise applies to --feed FILE only"),
        (["--feed", "f.csv", "--capture-interval", "0.2", "--start", "2026-11-26T10:00"],
         "--start: ISO 8601 timestamp without a UTC offset"),
        (["--feed", "f.csv", "--capture-interval", "0.2", "--noise", "-1"], "--noise must be"),
        (["--meters", "J1"], "--meters applies to --feed FILE only"),
        (["--feed", "f.csv", "--capture-interval", "0.2", "--meters", "J1,Q1", "Q2"],
         "2 meter(s) ['Q1', 'Q2'] are not junctions of"),
    ],
)  # fmt: skip
def test_bad_feed_options_are_named_before_any_work(
    extra: list[str], says: str, tiny: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pipe = [] if "--all" in extra else ["--pipe", "C"]
    assert _run("simulate", tiny, *pipe, "--out", tmp_path / "o", *extra) == 2
    assert says in capsys.readouterr().err
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_a_capture_interval_finer_than_tsnet_s_step_gets_a_step_fine_enough(
    tmp_path: Path,
) -> None:
    """paper15's TSNet step is 0.104 s: readings every 0.05 s ask for a step of half that, as
    `burstloc evaluate` does, instead of a refusal."""
    paper15 = Path(__file__).resolve().parents[2] / "networks" / "paper15.inp"
    out = tmp_path / "out"
    code = _run(
        "simulate", paper15, "--pipe", "1", "--capture-interval", "0.05", "--out", out,
        "--no-cache", *SHORT,
    )  # fmt: skip
    assert code == 0
    with np.load(out / "paper15_pipe-1.npz", allow_pickle=False) as data:
        meta = json.loads(str(data["metadata"]))
        np.testing.assert_allclose(np.diff(data["time"]), 0.05)
    assert meta["time_step"] <= 0.05 and meta["capture_interval"] == 0.05


def test_a_network_epanet_solves_only_demand_driven_is_simulated_so_and_said(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # tests/demand_driven_only.inp: EPANET refuses its pressure law (tests/test_network.py)
    network = Path(__file__).resolve().parents[1] / "demand_driven_only.inp"
    out = tmp_path / "out"
    code = _run("simulate", network, "--pipe", "B", "--out", out, "--cache-dir", tmp_path / "c")
    assert code == 0  # was refused: "TSNet failed ... EpanetException: (Error 200) ..."
    said = capsys.readouterr().err
    assert (
        f"burstloc: warning: EPANET cannot solve {network} pressure-driven ((Error 200) one or "
        "more errors in input file): its steady state is solved demand-driven instead" in said
    ), said
    with np.load(out / "demand_driven_only_pipe-B.npz", allow_pickle=False) as data:
        heads = data["heads"]
        meta = json.loads(str(data["metadata"]))
    assert np.isfinite(heads).all() and heads[0] == pytest.approx([49.91, 49.84, 49.84], abs=0.01)
    recorded = [w for w in meta["warnings"] if w.startswith("DemandDrivenWarning: ")]
    assert len(recorded) == 2  # the network's steady state and the transient model's
    assert f"pipe 'B' of {network} split at 0.5 pressure-driven" in recorded[1]


def _four_meters(paper15: Path, tmp_path: Path) -> tuple[list[str], Path, list[str | Path]]:
    """Four meters of paper15, a configuration calibrated for them at 0.2 s, and the start of a
    ``simulate`` command line bursting P7 for 14 s, read at 0.2 s."""
    from burstloc.experiments.calibrate import calibrate

    meters = ["N4", "N7", "1", "8"]
    config = calibrate(paper15, capture_intervals=(0.2,), meters=meters).save(tmp_path / "c.json")
    args: list[str | Path] = ["simulate", paper15, "--pipe", "P7", "--duration", "14"]
    return meters, config, [*args, "--capture-interval", "0.2", "--quiet"]


def test_a_feed_carries_the_configurations_meters_or_the_ones_given(
    paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    meters, config, args = _four_meters(paper15, tmp_path)
    args += ["--out", tmp_path / "out"]
    every, mine, two = tmp_path / "every.csv", tmp_path / "mine.csv", tmp_path / "two.csv"
    assert _run(*args, "--feed", every) == 0
    assert f"wrote {15 * 70} readings of every junction to {every}" in capsys.readouterr().out
    assert _run(*args, "--feed", mine, "--config", config) == 0
    assert f"wrote {4 * 70} readings of 4 meters to {mine}" in capsys.readouterr().out
    rows = [line.split(",") for line in mine.read_text().splitlines()[1:]]
    assert [m for _, m, _ in rows[:4]] == meters and len(rows) == 4 * 70
    full = {(t, m): v for t, m, v in (ln.split(",") for ln in every.read_text().splitlines()[1:])}
    assert all(full[(t, m)] == v for t, m, v in rows)  # noiseless: the same readings
    done = _monitor(paper15, config, mine)
    assert done.returncode == 0, done.stderr
    assert "unknown meter" not in done.stderr
    decisions = [json.loads(line) for line in done.stdout.splitlines()]
    assert [d["type"] for d in decisions] == ["decision"]
    # --meters, in the order given (a text file of IDs), over the configuration's
    listed = tmp_path / "two.txt"
    listed.write_text("8\nN4  # by the tank\n")
    assert _run(*args, "--feed", two, "--config", config, "--meters", listed) == 0
    rows = [line.split(",") for line in two.read_text().splitlines()[1:]]
    assert [m for _, m, _ in rows[:2]] == ["8", "N4"] and len(rows) == 2 * 70


def test_a_burst_sized_by_its_flow(
    paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from burstloc.network import load_network
    from burstloc.sim.scenarios.result import ScenarioResult

    out = tmp_path / "out"
    args = ["simulate", paper15, "--pipe", "P7", "--duration", "11", "--out", out, "--quiet"]
    assert _run(*args, "--burst-flow", "5") == 0
    said = capsys.readouterr().out
    (path,) = out.glob("*.npz")
    meta = ScenarioResult.load(path).metadata
    assert meta["burst_flow_lps"] == pytest.approx(5.0)
    pressure = meta["burst_pressure_m"]
    assert meta["burst_coeff"] == pytest.approx(0.005 / np.sqrt(pressure))
    assert said.startswith(
        f"burst on P7: 5 L/s at the burst point's {pressure:.1f} m of pressure head before it "
        f"opens (emitter coefficient {meta['burst_coeff']:.3g} m^3/s/m^0.5)"
    )
    # the pressure before the burst: the simulation's own pressure heads at the pipe's ends
    # (its start node N5, its end node N7), halfway
    result = ScenarioResult.load(path)
    link = load_network(paper15).get_link("P7")
    assert (link.start_node_name, link.end_node_name) == ("N5", "N7")
    ends = [result.heads[0, list(result.junctions).index(n)] for n in ("N5", "N7")]
    assert pressure == pytest.approx(sum(ends) / 2, abs=0.05)
    # a coefficient: the flow it draws there is said and recorded too
    assert _run(*args, "--burst-coeff", "0.01") == 0
    flow = 10.0 * np.sqrt(pressure)
    assert capsys.readouterr().out.startswith(f"burst on P7: {flow:.3g} L/s at the burst point's")
    meta = ScenarioResult.load(path).metadata
    assert meta["burst_flow_lps"] == pytest.approx(10.0 * np.sqrt(pressure), rel=1e-6)
    assert _run(*args, "--burst-flow", "-1") == 2
    assert "--burst-flow must be a positive number of L/s" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        _run(*args, "--burst-flow", "5", "--burst-coeff", "0.01")
    capsys.readouterr()
    # neither: the default burst, 5 % of the demand (248 L/s) capped at 5 L/s, said and
    # recorded like a chosen one
    assert _run(*args) == 0
    default = "5 % of the network's demand, at most 5 L/s"
    assert capsys.readouterr().out.startswith(f"burst on P7: 5 L/s ({default}) at the burst")
    meta = ScenarioResult.load(path).metadata
    assert meta["burst_flow_lps"] == pytest.approx(5.0)
    assert meta["burst_coeff"] == pytest.approx(0.005 / np.sqrt(pressure))
    assert meta["burst_sizing"] == default
    # a share of the demand, uncapped: 1 % of paper15's 248 L/s
    assert _run(*args, "--burst-share", "1") == 0
    assert capsys.readouterr().out.startswith(
        "burst on P7: 2.48 L/s (1 % of the network's demand) at the burst"
    )
    assert ScenarioResult.load(path).metadata["burst_flow_lps"] == pytest.approx(2.48, abs=0.01)
    assert _run(*args, "--burst-share", "120") == 2
    assert "--burst-share must be a percentage in (0, 100], got 120" in capsys.readouterr().err


def test_a_burst_the_network_cannot_feed_is_said(
    tiny_network: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    args = ["simulate", tiny_network, "--pipe", "B", "--burst-start", "0.2", "--duration", "2"]
    args += ["--opening-time", "0", "--solver", "tsnet", "--out", tmp_path / "o", "--quiet"]
    assert _run(*args, "--burst-coeff", "0.02") == 0  # large and instant: below zero
    err = capsys.readouterr().err
    assert "burstloc: warning: burst on pipe B: negative pressure at " in err
    assert "the burst point on pipe B" in err and "B_B" not in err
    assert _run(*args, "--burst-flow", "1", "--no-cache") == 0  # 1 L/s: fed
    assert "negative pressure" not in capsys.readouterr().err


def test_a_feed_from_a_perturbed_truth_shifts_the_clocks_and_silences_the_nearest_meter(
    paper15: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    meters, config, bare = _four_meters(paper15, tmp_path)
    args = [*bare, "--config", config]
    plain, truth = tmp_path / "plain.csv", tmp_path / "truth.csv"
    assert _run(*args, "--out", tmp_path / "a", "--feed", plain) == 0
    perturbed = ["--truth-clock-offset", "0.05", "--truth-silent-meter", "2", "--truth-seed", "4"]
    assert _run(*args, "--out", tmp_path / "b", "--feed", truth, *perturbed) == 0
    assert "truth perturbed: meter clocks off by N(0, (50 ms)²)" in capsys.readouterr().out

    def readings(path: Path) -> dict[str, dict[float, float]]:
        found: dict[str, dict[float, float]] = {}
        for line in path.read_text().splitlines()[1:]:
            t, m, v = line.split(",")
            found.setdefault(m, {})[float(t)] = float(v)
        return found

    was, now = readings(plain), readings(truth)
    assert set(now) == set(meters)
    silent = [m for m in meters if len(now[m]) < len(was[m])]
    assert len(silent) == 1  # the meter nearest the burst sends nothing from 2 s after it
    assert max(now[silent[0]]) == pytest.approx(11.8) and len(was[silent[0]]) == 70
    # before the burst the heads are steady: a shifted clock reads the same; after, not
    before = [abs(now[m][t] - was[m][t]) for m in meters for t in now[m] if t < 9.8]
    after = [abs(now[m][t] - was[m][t]) for m in meters for t in now[m] if t > 10.0]
    assert max(before) < 0.002 < max(after)
    # the scenario file is the simulation, not the meters: the same in both runs
    (a,) = (tmp_path / "a").glob("*.npz")
    (b,) = (tmp_path / "b").glob("*.npz")
    assert np.array_equal(np.load(a)["heads"], np.load(b)["heads"])
    done = _monitor(paper15, config, truth)
    assert done.returncode == 0, done.stderr
    decisions = [json.loads(line) for line in done.stdout.splitlines()]
    assert [d["type"] for d in decisions] == ["decision"]
    # the clocks and the silent meter act on the feed: without one they would act on nothing
    assert _run(*bare, "--out", tmp_path / "d", *perturbed) == 2
    err = capsys.readouterr().err
    assert "--truth-clock-offset and --truth-silent-meter act on the meters' readings" in err
    assert not (tmp_path / "d").exists() or not list((tmp_path / "d").glob("*.npz"))
    # an operation's simulation has no perturbed truth
    event = ["simulate", paper15, "--event", "demand-step", "--asset", "N4", "--quiet"]
    assert _run(*event, "--out", tmp_path / "c", "--truth-clock-offset", "0.01") == 2
    assert "--truth-* options apply to bursts only" in capsys.readouterr().err
