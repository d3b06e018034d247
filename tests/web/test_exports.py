"""The page server's exports over real HTTP from a real ``burstloc monitor --web`` process fed a
real burst: ``/metrics`` parsed by the Prometheus client's own parser, its values those of the
replay; ``/region.geojson`` the current record as ``burstloc.gis`` draws it, in WGS 84."""

from __future__ import annotations

import json
import sys
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from web_browser import Monitor, wait_for

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from burstloc.gis import record_geojson
from burstloc.incidents import IncidentStore, Outcome
from burstloc.layout import read_layout
from utm_network import CRS, burst, utm_copy

parser = pytest.importorskip("prometheus_client.parser")
pytest.importorskip("pyproj")


@pytest.fixture(scope="module")
def replay(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, list[str], int]:
    """(network, configuration, CSV lines, steps) of a real burst on paper15 drawn in UTM."""
    folder = tmp_path_factory.mktemp("exports")
    network = utm_copy(folder)
    calibration, steps = burst(network)
    config = calibration.save(folder / "paper15_utm.json")
    lines = [
        f"{s.timestamp:.1f},{m},{float(v):.4f}"
        for s in steps
        for m, v in zip(calibration.meters, s.values, strict=True)
    ]
    return network, config, lines, len(steps)


@pytest.fixture
def monitor(replay: tuple[Path, Path, list[str], int]) -> Iterator[Any]:
    started: list[Monitor] = []

    def start(*options: str) -> Monitor:
        started.append(Monitor(replay[0], replay[1], "--web", "127.0.0.1:0", *options))
        return started[-1]

    yield start
    for m in started:
        m.stop()


def _get(url: str, token: str | None = None) -> tuple[int, dict[str, str], bytes]:
    request = urllib.request.Request(url)
    if token is not None:
        request.add_header("Authorization", f"Bearer {token}")
    try:
        with urllib.request.urlopen(request, timeout=30) as response:
            return response.status, dict(response.headers), response.read()
    except urllib.error.HTTPError as exc:
        return exc.code, dict(exc.headers), exc.read()


def _samples(text: str) -> dict[tuple[str, tuple[tuple[str, str], ...]], float]:
    """Every sample of the exposition, by (name, sorted labels), parsed by prometheus_client."""
    out = {}
    for family in parser.text_string_to_metric_families(text):
        for sample in family.samples:
            out[(sample.name, tuple(sorted(sample.labels.items())))] = sample.value
    return out


def _metrics(m: Monitor, token: str | None = None) -> dict[Any, float]:
    status, headers, body = _get(m.url.split("?")[0] + "metrics", token)
    assert status == 200, body
    assert headers["content-type"].startswith("text/plain; version=0.0.4")
    return _samples(body.decode())


def test_metrics_after_a_real_replay_are_its_counts(
    monitor: Any, replay: tuple[Path, Path, list[str], int]
) -> None:
    network, _, lines, steps = replay
    m = monitor("--crs", CRS, "--health-every", "0")
    base = m.url.split("?")[0]
    wait_for(lambda: _get(base + "metrics")[0] == 200, "the metrics served")  # 503 at the start
    status, _, body = _get(base + "region.geojson")
    assert status == 404 and b"nothing located yet" in body
    m.feed(lines)
    decision = m.record("decision")
    done = wait_for(
        lambda: (s := _metrics(m))[("burstloc_steps_total", ())] == steps and s,
        f"all {steps} steps counted",
    )
    meters = decision["meters"]
    assert done[("burstloc_readings_total", ())] == len(lines) == steps * len(meters)
    for meter in meters:
        assert done[("burstloc_meter_readings_total", (("meter", meter),))] == steps
        assert done[("burstloc_meter_silent", (("meter", meter),))] == 0
    assert done[("burstloc_meters", ())] == len(meters)
    assert done[("burstloc_decisions_total", ())] == 1
    assert done[("burstloc_silent_meters", ())] == 0
    assert done[("burstloc_late_readings_total", ())] == 0
    for reason in ("bad", "implausible", "off_clock", "unknown_meter"):
        assert done[("burstloc_bad_readings_total", (("reason", reason),))] == 0
    latency = ("burstloc_decision_latency_seconds_count", (("record", "decision"),))
    assert done[latency] == 1
    spent = done[("burstloc_decision_latency_seconds_sum", (("record", "decision"),))]
    assert 0 < spent < 60
    inf = ("burstloc_decision_latency_seconds_bucket", (("le", "+Inf"), ("record", "decision")))
    assert done[inf] == 1
    assert done[("burstloc_decision_delay_seconds_sum", ())] == pytest.approx(
        decision["decision_delay_s"]
    )
    assert done[("burstloc_feed_time_seconds", ())] == pytest.approx(float(lines[-1].split(",")[0]))
    assert done[("burstloc_queue_capacity", (("queue", "page"),))] > 0
    assert done[("burstloc_holding_off", ())] in (0, 1)
    info = [k for k in done if k[0] == "burstloc_info"]
    assert dict(info[0][1])["network"] == network.name and dict(info[0][1])["detector"] == "cusum"
    assert not [k for k in done if k[0] == "burstloc_incidents_open"]  # no incident store
    assert done[("process_resident_memory_bytes", ())] > 0

    # bad readings of each kind, counted by reason
    t = float(lines[-1].split(",")[0]) + 0.2
    m.feed([f"{t:.1f},{meters[0]},abc", f"{t:.1f},Z9,50.0", f"{t:.1f},{meters[1]},1e6"])
    implausible = ("burstloc_bad_readings_total", (("reason", "implausible"),))
    bad = wait_for(lambda: (s := _metrics(m))[implausible] == 1 and s, "the last one counted")
    assert bad[("burstloc_bad_readings_total", (("reason", "bad"),))] == 1
    assert bad[("burstloc_bad_readings_total", (("reason", "unknown_meter"),))] == 1

    # the current record for GIS: as burstloc.gis draws it, in WGS 84
    status, headers, body = _get(base + "region.geojson")
    assert status == 200 and headers["content-type"] == "application/geo+json"
    assert 'filename="burstloc-decision-' in headers["content-disposition"]
    expected = record_geojson(read_layout(network), decision, crs=CRS)
    assert json.loads(body) == json.loads(json.dumps(expected))


def test_the_exports_need_the_token_when_there_is_one(monitor: Any) -> None:
    m = monitor("--web-token", "s3cret")
    base = m.url.split("?")[0]
    for path in ("metrics", "region.geojson"):
        status, _, body = _get(base + path)
        assert status == 401 and body == b"unauthorized"
        assert _get(base + path, "wrong")[0] == 401
    wait_for(lambda: _get(base + "metrics", "s3cret")[0] == 200, "the metrics served")
    assert _get(base + "region.geojson", "s3cret")[0] == 404  # authorized; nothing located yet


def test_a_crs_without_the_page_or_unknown_is_refused(
    replay: tuple[Path, Path, list[str], int],
) -> None:
    import subprocess

    network, config, _, _ = replay
    base = [sys.executable, "-m", "burstloc", "monitor", str(network), "--config", str(config),
            "--capture-interval", "0.2", "--readings", "-"]  # fmt: skip
    for extra, text in [
        (["--crs", CRS], "--crs is for the page's GeoJSON download: it needs --web"),
        (["--crs", "EPSG:99999", "--web", "127.0.0.1:0"], "'EPSG:99999' is not a coordinate"),
    ]:
        done = subprocess.run(base + extra, input="", capture_output=True, text=True, check=False)
        assert done.returncode == 2 and text in done.stderr, done.stderr


def test_the_open_incidents_are_a_gauge_with_a_store(
    monitor: Any, replay: tuple[Path, Path, list[str], int], tmp_path: Path
) -> None:
    _, _, lines, _ = replay
    m = monitor("--health-every", "0", "--db", str(tmp_path / "incidents.sqlite"))
    wait_for(lambda: _get(m.url.split("?")[0] + "metrics")[0] == 200, "the metrics served")
    assert _metrics(m)[("burstloc_incidents_open", ())] == 0
    m.feed(lines)
    decision = m.record("decision")
    opened = ("burstloc_incidents_open", ())
    wait_for(lambda: _metrics(m)[opened] >= 1, "the located burst an open incident")
    meters, alarmed = decision["meters"], set(decision["alarmed"])

    def false_alarms(samples: dict[Any, float]) -> dict[str, float]:
        return {k: samples[("burstloc_meter_false_alarms", (("meter", k),))] for k in meters}

    before = _metrics(m)
    assert false_alarms(before) == {k: 0 for k in meters}
    for k in meters:  # every configured meter is there; those that alarmed made one incident
        assert before[("burstloc_meter_alarmed_incidents", (("meter", k),))] == (k in alarmed)
    # an operator closes it as a false alarm (another process, as `burstloc incidents` does)
    store = IncidentStore.open(str(tmp_path / "incidents.sqlite"))
    try:
        (row,) = store.incidents()
        store.acknowledge(row["id"], "ann", "cli")
        store.close_incident(row["id"], "ann", "cli", Outcome.false_alarm())
    finally:
        store.close()
    after = _metrics(m)
    assert false_alarms(after) == {k: float(k in alarmed) for k in meters}
    assert after[opened] == 0  # counted by the store at each scrape: none open now
