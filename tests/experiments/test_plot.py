"""burstloc.experiments.plot: the evaluation's maps and traces, and the study's accuracy plot,
written as real PNG files."""

from __future__ import annotations

from pathlib import Path

from burstloc.experiments.evaluate import Evaluation, RunResult
from burstloc.experiments.harness import locate_burst
from burstloc.experiments.plot import plot_accuracy_by_interval, write_plots
from burstloc.experiments.runs import RunSpec
from burstloc.localize.detection import DetectorConfig
from synthetic_bursts import small_graph, synthetic

PNG = b"\x89PNG\r\n\x1a\n"


def _evaluation() -> Evaluation:
    graph = small_graph()
    spec = RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5)
    results = {
        "pB": synthetic("pB", {"B": (3.0, 0.2), "A": (1.0, 0.2)}),  # named right
        "pD": synthetic("pD", {}),  # not located
    }
    attempts = {p: [locate_burst(r, graph, spec)] for p, r in results.items()}
    truth = {"pB": ("A", "B"), "pD": ("B", "C")}
    run = RunResult(spec, list(results), truth, [0.0], attempts)
    return Evaluation("nets/line.inp", [run], {}, "capture", [], results, graph)


def test_write_plots_writes_a_map_and_traces_per_run(tmp_path: Path) -> None:
    ev = _evaluation()
    assert ev.runs[0].attempts["pB"][0].correct and not ev.runs[0].attempts["pD"][0].located
    paths = write_plots(ev, tmp_path / "plots")
    assert [p.name for p in paths] == [
        "line_cusum_window_0p2s_network.png",
        "line_cusum_window_0p2s_traces_pB.png",
    ]
    for path in paths:
        assert path.read_bytes()[:8] == PNG and path.stat().st_size > 5000
    # the traces of a burst that was not located, chosen by name
    (other,) = [p for p in write_plots(ev, tmp_path / "more", pipe="pD") if "traces" in p.name]
    assert other.name.endswith("_traces_pD.png") and other.read_bytes()[:8] == PNG
    assert sorted(p.name for p in (tmp_path / "plots").iterdir()) == sorted(p.name for p in paths)


def test_accuracy_by_interval_has_one_panel_per_meter_model(tmp_path: Path) -> None:
    rows = [
        {"meter_model": model, "capture_interval": dt, "top1": top1, "localizer": "fused"}
        for model in ("instantaneous", "interval-averaged")
        for dt, top1 in ((0.2, 1.0), (2.0, 0.8), (10.0, 0.4))
    ]
    one = plot_accuracy_by_interval(rows[:3], tmp_path / "one.png", "t", ["localizer"])
    two = plot_accuracy_by_interval(rows, tmp_path / "two.png", "t", ["localizer"])
    for path in (one, two):
        assert path.read_bytes()[:8] == PNG

    def width(path: Path) -> int:
        return int.from_bytes(path.read_bytes()[16:20], "big")  # the PNG header's width

    assert width(two) > 1.8 * width(one)


def test_the_traces_say_what_a_ranking_localizer_said(tiny: Path, tmp_path: Path) -> None:
    # Before, every ranking localizer's traces were titled "not located", whatever it named.
    from burstloc.experiments import paper
    from burstloc.experiments.calibrate import calibrate
    from burstloc.experiments.evaluate import evaluate
    from burstloc.experiments.plot import trace_title

    config = calibrate(tiny, capture_intervals=[0.2], noise_sigma=0.01, max_samples=300_000)
    spec = RunSpec(DetectorConfig("cusum", 0.3), 0.2, 5, localizer="arrival")
    ev = evaluate(
        tiny,
        [spec],
        pipes=["C"],
        phases=1,
        scenario=paper.ScenarioConfig(burst_start=2.0),
        config=config,
        workers=1,
        progress=False,
    )
    run = ev.runs[0]
    attempt = run.attempts["C"][0]
    assert attempt.decision is not None and attempt.predicted_pipe is not None
    title = trace_title(run, "C", attempt.burst_start)
    verdict = "correct" if attempt.correct else "wrong"
    assert title.startswith(f"pipe C burst: named {attempt.predicted_pipe}, {verdict}"), title
    assert "arrival localizer" in title and "not located" not in title
    paths = write_plots(ev, tmp_path / "plots")
    assert [p.read_bytes()[:8] for p in paths] == [PNG, PNG]
