"""``burstloc monitor --web``: the control-room page in a real browser (Debian's Chromium driven
by Selenium) over a real monitor process fed a real simulated burst on its stdin."""

from __future__ import annotations

import math
import subprocess
import sys
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from web_browser import ROOT, Monitor, chromium, csv_lines, page_state, wait_for

from burstloc.inp import pipe_names_in_file
from burstloc.localize.config import Calibration

PAPER15 = ROOT / "networks" / "paper15.inp"
METERS = ("N3", "N5", "N8", "2", "4", "6", "8")
BURST_PIPE = "9"
ONSET_STEPS = 300  # 60 s of steady readings before the burst (live_feed.burst_steps)


@pytest.fixture(scope="module")
def config(tmp_path_factory: pytest.TempPathFactory) -> tuple[Calibration, Path]:
    from burstloc.experiments.calibrate import calibrate

    calibration = calibrate(PAPER15, capture_intervals=(0.2,), noise_sigma=0.01, meters=METERS)
    path = tmp_path_factory.mktemp("config") / "paper15.json"
    calibration.save(path)
    return calibration, path


@pytest.fixture(scope="module")
def feed(config: tuple[Calibration, Path]) -> list[str]:
    """A real TSNet burst on pipe 9, as CSV readings: 60 s steady, the burst, 200 s after."""
    from live_feed import burst_steps

    steps = burst_steps(PAPER15, config[0].meters, BURST_PIPE, sigma=0.003, after=200.0)
    return csv_lines(steps, config[0].meters)


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    with chromium(tmp_path_factory.mktemp("chromium")) as driver:
        yield driver


@pytest.fixture
def monitor(config: tuple[Calibration, Path], request: pytest.FixtureRequest) -> Iterator[Any]:
    """Start ``burstloc monitor --web 127.0.0.1:0 OPTIONS`` (``monitor(*options)``)."""
    started: list[Monitor] = []

    def start(*options: str, env: dict[str, str] | None = None) -> Monitor:
        started.append(Monitor(PAPER15, config[1], "--web", "127.0.0.1:0", *options, env=env))
        return started[-1]

    yield start
    for m in started:
        m.stop()


def _ready(driver: Any) -> dict[str, Any]:
    return wait_for(lambda: (s := page_state(driver)).get("ready") and s, "the page is ready")


def test_the_page_draws_every_pipe(browser: Any, monitor: Any) -> None:
    m = monitor()
    browser.get(m.url)
    state = _ready(browser)
    pipes = pipe_names_in_file(PAPER15)
    assert state["pipes"] == state["drawnPipes"] == len(pipes) == 25
    assert set(state["meterStatus"]) == set(METERS)
    assert browser.find_element("id", "map").size["width"] > 300


def test_pumps_valves_and_sources_are_drawn(browser: Any) -> None:
    from burstloc.web import control_room

    network = ROOT / "networks" / "paper15_assets.inp"
    server = control_room(network, ["N3"], 0.2)
    server.start()
    try:
        browser.get(server.url)
        state = _ready(browser)
        kinds = browser.execute_script("return net.links.kinds.concat(net.nodes.kinds)")
    finally:
        server.stop()
    assert state["drawnPipes"] == len(pipe_names_in_file(network)) == 27
    assert state["links"] == 29
    assert {"pump", "valve", "reservoir", "junction"} <= set(kinds)


def test_a_burst_is_highlighted_and_a_second_browser_joining_sees_it(
    browser: Any, monitor: Any, feed: list[str], tmp_path: Path
) -> None:
    m = monitor()
    lines_per_step = len(METERS)
    m.feed(feed[: ONSET_STEPS * lines_per_step])
    browser.get(m.url)
    _ready(browser)
    assert page_state(browser)["highlighted"] is None
    m.feed(feed[ONSET_STEPS * lines_per_step :])
    record = m.record("decision")
    pipe = record["pipes"][0]["pipe"]
    assert pipe == BURST_PIPE  # the monitor located it; now the page must show it

    def shown(driver: Any) -> dict[str, Any] | None:
        s = page_state(driver)
        ok = s.get("highlighted") == pipe and s.get("region") and s.get("position")
        return s if ok and s["answer"] and s["answer"]["time"] == record["time"] else None

    first = wait_for(lambda: shown(browser), f"pipe {pipe} highlighted")
    region = first["region"]["stretches"]
    # the record's search region, drawn stretch by stretch, with its confidence
    assert [(r["pipe"], r["low"], r["high"]) for r in region] == [
        (r["pipe"], r["low"], r["high"]) for r in record["region"]["stretches"]
    ]
    assert first["region"]["confidence"] == record["region"]["confidence"] == 0.95
    alarmed = [a["meter"] for a in first["alarms"]]
    assert sorted(alarmed) == sorted(record["alarmed"])
    times = [a["time"] for a in first["alarms"]]
    assert times == sorted(times) and times[0] == pytest.approx(record["first_alarm"])
    # the panels (redrawn a moment after the map): the answer and the log
    wait_for(
        lambda: (
            (text := browser.find_element("id", "answer").text.upper()).startswith("BURST")
            and f"PIPE {pipe}\n" in text
            # the page rounds half up (JavaScript's toFixed), Python's format half to even
            and f"SEARCH REGION {math.floor(record['region']['length_m'] + 0.5)} M" in text
        ),
        "the incident panel names the pipe and the search region",
    )
    wait_for(
        lambda: f"burst located on pipe {pipe}" in browser.find_element("id", "log").text,
        "the log tells the decision",
    )

    with chromium(tmp_path / "second") as second:  # joins after the decision
        second.get(m.url)
        _ready(second)
        late = wait_for(lambda: shown(second), "the second browser shows the same")
    for key in ("highlighted", "region", "position", "alarms", "answer", "meterStatus"):
        assert late[key] == first[key], key


def test_a_silent_meter_shows_as_silent(
    browser: Any, monitor: Any, feed: list[str], config: tuple[Calibration, Path]
) -> None:
    m = monitor("--silent-after", "5")
    steady = feed[: ONSET_STEPS * len(METERS)]
    lines = []
    for line in steady:
        t, meter, _ = line.split(",")
        if meter == "N8" and float(t) > 10:
            continue  # N8 goes quiet after 10 s
        if meter == "2" and float(t) == 20.0:
            line = f"{t},{meter},9999.0"  # one implausible reading
        lines.append(line)
    m.feed(lines)
    browser.get(m.url)
    _ready(browser)

    def statuses() -> dict[str, str] | None:
        s = page_state(browser)["meterStatus"]
        return s if s.get("N8") == "silent" and s.get("2") == "implausible" else None

    status = wait_for(statuses, "N8 shown silent and 2 implausible")
    assert {k for k, v in status.items() if v == "ok"} == set(METERS) - {"N8", "2"}
    table = (  # the health table's state column, read at once (it is redrawn as news come)
        "return Object.fromEntries([...document.querySelectorAll('#health tr[data-m]')]"
        ".map((r) => [r.dataset.m, r.querySelector('td[data-status]').dataset.status]))"
    )
    cells = wait_for(
        lambda: (c := browser.execute_script(table)).get("N8") == "silent" and c,
        "the health table says N8 is silent",
    )
    assert set(cells) == set(METERS) and cells["2"] == "implausible"
    assert any("N8" in line and "silent" in line for line in m.stderr)


def test_a_replayed_file_shows_the_burst_located_and_the_page_stays_up(
    browser: Any, monitor: Any, feed: list[str], tmp_path: Path
) -> None:
    readings = tmp_path / "demo.csv"
    readings.write_text("\n".join(feed) + "\n")
    m = monitor("--readings", str(readings), "--replay-speed", "40")
    browser.get(m.url)
    _ready(browser)
    record = m.record("decision")
    wait_for(
        lambda: page_state(browser).get("highlighted") == record["pipes"][0]["pipe"],
        "the replayed burst is shown",
    )
    wait_for(lambda: any("page stays up" in line for line in m.stderr), "the feed ends")
    browser.refresh()  # the page is still served after the last reading
    assert _ready(browser)["answer"]["time"] == record["time"]
    m.proc.terminate()
    assert m.proc.wait(timeout=60) == 0
    wait_for(lambda: any("stopped by SIGTERM" in line for line in m.stderr), "told")


def _get(url: str, method: str = "GET", headers: dict[str, str] | None = None) -> tuple[int, bytes]:
    request = urllib.request.Request(url, method=method, headers=headers or {})
    try:
        with urllib.request.urlopen(request, timeout=30) as response:
            body = response.read(1) if "/events" in url else response.read()  # a stream
            return response.status, body
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read()


@pytest.mark.parametrize("how", ["option", "environment"])
def test_a_wrong_or_missing_token_gets_401_and_nothing_else(
    browser: Any, monitor: Any, how: str
) -> None:
    secret = "s3cret-token"
    if how == "option":
        m = monitor("--web-token", secret)
    else:
        m = monitor(env={"BURSTLOC_WEB_TOKEN": secret})
    base = m.url.split("?")[0].rstrip("/")
    for path in ("/", "/static/app.js", "/static/style.css", "/network.json", "/state.json"):
        for query, headers in [
            ("", {}),
            ("?token=wrong", {}),
            ("", {"Authorization": "Bearer wrong"}),
            ("?token=s3cret-toke", {}),
        ]:
            assert _get(base + path + query, headers=headers) == (401, b"unauthorized"), path
        status, body = _get(f"{base}{path}?token={secret}")
        assert status == 200 and body, path
    assert _get(base + "/events")[0] == 401
    assert _get(f"{base}/events?token={secret}")[0] == 200
    assert _get(base + "/", headers={"Authorization": f"Bearer {secret}"})[0] == 200
    # read-only: nothing but GET
    for method in ("POST", "PUT", "DELETE"):
        assert _get(f"{base}/state.json?token={secret}", method=method)[0] == 405
    browser.get(base + "/?token=wrong")
    # Chromium may hand the text view over before its text is in: waited for, not read at once
    wait_for(lambda: "unauthorized" in browser.page_source, "the browser shows the 401's text")
    assert browser.execute_script("return typeof window.burstloc") == "undefined"
    browser.get(f"{base}/?token={secret}")
    _ready(browser)
    browser.get(base + "/")  # the cookie the first load set carries the token
    _ready(browser)


def test_a_public_address_needs_a_token(config: tuple[Calibration, Path]) -> None:
    command = [
        sys.executable, "-m", "burstloc", "monitor", str(PAPER15), "--config", str(config[1]),
        "--capture-interval", "0.2", "--readings", "-", "--web", "0.0.0.0:0",
    ]  # fmt: skip
    proc = subprocess.run(command, input="", capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0
    assert "needs a token" in proc.stderr and "BURSTLOC_WEB_TOKEN" in proc.stderr
    assert "control room at" not in proc.stderr


def test_an_mqtt_feed_is_shown_alike(
    browser: Any, monitor: Any, feed: list[str], tmp_path: Path
) -> None:
    import queue

    import paho.mqtt.client as mqtt
    from mosquitto import SUBSCRIPTIONS, broker
    from paho.mqtt.enums import CallbackAPIVersion

    steps = [
        "\n".join(feed[k : k + len(METERS)]).encode() for k in range(0, len(feed), len(METERS))
    ]
    with broker(tmp_path) as port:
        logged: queue.Queue[str] = queue.Queue()
        sender = mqtt.Client(CallbackAPIVersion.VERSION2, client_id="sender")
        sender.on_message = lambda c, u, message: logged.put(message.payload.decode())
        sender.connect("127.0.0.1", port)
        sender.subscribe(SUBSCRIPTIONS, qos=1)
        sender.loop_start()
        m = monitor("--mqtt", f"127.0.0.1:{port}", "--topic", "plant/readings/#")
        try:
            browser.get(m.url)
            _ready(browser)

            def subscribed() -> bool:  # readings sent before it would be lost
                try:
                    return logged.get(timeout=0.5).endswith(" plant/readings/#")
                except queue.Empty:
                    assert m.proc.poll() is None, "".join(m.stderr)
                    return False

            wait_for(subscribed, "the monitor's subscription")
            for payload in steps:
                sender.publish("plant/readings/all", payload, qos=1)
            try:
                wait_for(
                    lambda: browser.execute_script("return rows.length"),
                    "the first readings through the broker",
                )
            except AssertionError as exc:
                raise AssertionError(f"{exc}; the monitor said: {''.join(m.stderr)}") from None
            record = m.record("decision")
            wait_for(
                lambda: page_state(browser).get("highlighted") == record["pipes"][0]["pipe"],
                "the burst read from the broker is shown",
            )
        finally:
            sender.loop_stop()
            m.stop()
