"""What the control-room page shows, where it used to mislead, in a real browser (Debian's
Chromium): the named pipe above the search region, the panel's count of the region's pipes as
the record's, the names of pipes and meters once zoomed in, the early region and when the answer
is due while the monitor waits, and the snapshot view for a picture (no event stream)."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from test_control_room import METERS, ONSET_STEPS, PAPER15, browser, config, feed  # noqa: F401
from test_picture import kept  # noqa: F401 (a real burst kept by a real monitor run)
from web_browser import Monitor, page_state, wait_for

from burstloc.localize.config import Calibration

NAMED = (0xFF, 0x2D, 0x55)  # the page's COLORS.named
REGION = (0xFF, 0xD2, 0x3F)  # COLORS.region


def _ready(driver: Any) -> dict[str, Any]:
    return wait_for(lambda: (s := page_state(driver)).get("ready") and s, "the page is ready")


@pytest.fixture
def served(kept: tuple[Path, int, dict]) -> Iterator[Any]:  # noqa: F811
    """The page (in this process) over the store of :func:`kept`; its hub takes records."""
    from burstloc.incidents.store import IncidentStore
    from burstloc.web import control_room

    store = IncidentStore.open(str(kept[0]))
    server = control_room(PAPER15, kept[2]["meters"], 0.2, incidents=store)
    server.start()
    try:
        yield server
    finally:
        server.stop()
        store.close()


def _pixel(driver: Any, pipe: str, start: str, fraction: float) -> tuple[int, int, int]:
    """The map's colour (device pixels) at ``fraction`` along ``pipe`` from node ``start``."""
    return tuple(
        driver.execute_script(
            "const p = pointAt(arguments[0], arguments[1], arguments[2]);"
            "const d = window.devicePixelRatio || 1;"
            "const x = Math.round(sx(p[0]) * d), y = Math.round(sy(p[1]) * d);"
            "return Array.from(map.getContext('2d').getImageData(x, y, 1, 1).data).slice(0, 3);",
            pipe,
            start,
            fraction,
        )
    )


def _near(rgb: tuple[int, ...], want: tuple[int, int, int], within: int = 8) -> bool:
    return all(abs(a - b) <= within for a, b in zip(rgb, want, strict=True))


def test_the_named_pipe_is_above_the_region_and_the_panel_counts_the_records_pipes(
    browser: Any,  # noqa: F811
    served: Any,
    kept: tuple[Path, int, dict],  # noqa: F811
) -> None:
    _, incident, record = kept
    region = record["region"]
    pipes = {s["pipe"] for s in region["stretches"]}
    # the case that misled: a pipe holding two stretches (the page counted stretches)
    assert region["pipe_count"] == len(pipes) < len(region["stretches"])
    browser.get(served.url)
    _ready(browser)
    served.hub.record(record)
    pipe = record["pipes"][0]["pipe"]
    state = wait_for(
        lambda: (s := page_state(browser)).get("highlighted") == pipe and s.get("region") and s,
        "the record is drawn",
    )
    assert state["region"]["pipes"] == len(pipes) and state["region"]["missing"] == []
    wait_for(
        lambda: f"of main on {len(pipes)} pipe(s)" in browser.find_element("id", "answer").text,
        "the panel counts the record's pipes",
    )
    wait_for(  # the frame that drew the record (the map is drawn on the next animation frame)
        lambda: any(
            h["pipe"] == pipe and h.get("drawn") for h in page_state(browser)["highlights"]
        ),
        "the record's frame drawn",
    )
    # a point of the named pipe inside its stretch of the region, away from the position mark
    stretch = next(s for s in region["stretches"] if s["pipe"] == pipe)
    length = record["position"]["length"]
    marked = record["position"]["metres"]
    if stretch["from"] != record["position"]["from"]:
        marked = length - marked
    inside = [stretch["low"] + k * (stretch["high"] - stretch["low"]) / 20 for k in range(2, 19)]
    metres = max(inside, key=lambda m: abs(m - marked))
    assert abs(metres - marked) > 0.15 * length
    colour = _pixel(browser, pipe, stretch["from"], metres / length)
    assert _near(colour, NAMED), colour
    # and another pipe of the region is shown in the region's colour (drawn at 90 % opacity)
    other = next(s for s in region["stretches"] if s["pipe"] != pipe)
    middle = (
        (other["low"] + other["high"])
        / 2
        / browser.execute_script(
            "return net.links.length[net.linkIndex[arguments[0]]]", other["pipe"]
        )
    )
    assert _near(_pixel(browser, other["pipe"], other["from"], middle), REGION, 24)

    # the snapshot view of the same incident: drawn alike, without the event stream
    browser.get(served.url + f"?snapshot={incident}")
    snap = wait_for(lambda: (s := page_state(browser)).get("ready") and s, "the snapshot")
    assert snap["snapshot"] == str(incident) and not snap["connected"]
    assert snap["highlighted"] == pipe and snap["region"]["pipes"] == len(pipes)
    assert browser.find_element("tag name", "body").get_attribute("data-ready") == "1"
    requested = browser.execute_script(
        "return performance.getEntriesByType('resource').map((e) => new URL(e.name).pathname)"
    )
    assert "/events" not in requested and "/incidents.json" not in requested
    assert f"/incidents/{incident}.json" in requested
    assert snap["pipeLabels"] >= len(pipes)  # the crew's picture names the region's pipes
    assert f"of main on {len(pipes)} pipe(s)" in browser.find_element("id", "answer").text


def _grid(folder: Path, n: int = 30, spacing: float = 100.0) -> Path:
    """An n-by-n grid of junctions fed from one reservoir: 2n(n-1)+1 pipes (L-TOWN has 905)."""
    junctions = [f"J{i}_{j}" for i in range(n) for j in range(n)]
    pipes = [
        (f"P{a}-{b}", a, b)
        for i in range(n)
        for j in range(n)
        for a, b in [(f"J{i}_{j}", f"J{i + 1}_{j}"), (f"J{i}_{j}", f"J{i}_{j + 1}")]
        if b in junctions
    ]
    pipes.append(("PR", "R", "J0_0"))
    lines = ["[JUNCTIONS]", *(f" {j} 10 0.1" for j in junctions), "[RESERVOIRS]", " R 60",
             "[PIPES]", *(f" {p} {a} {b} {spacing:g} 150 100 0 Open" for p, a, b in pipes),
             "[COORDINATES]", " R -100 -100"]  # fmt: skip
    lines += [f" J{i}_{j} {i * spacing:g} {j * spacing:g}" for i in range(n) for j in range(n)]
    path = folder / "grid.inp"
    path.write_text("\n".join([*lines, "[END]"]) + "\n")
    return path


def test_pipe_and_meter_names_appear_once_zoomed_in_not_at_the_full_view(
    browser: Any,  # noqa: F811
    tmp_path: Path,
) -> None:
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.actions.wheel_input import ScrollOrigin

    from burstloc.web import control_room

    grid = _grid(tmp_path)
    server = control_room(grid, ["J3_3", "J20_25"], 0.2)
    server.start()
    try:
        browser.get(server.url)
        full = _ready(browser)
        # at the full view a pipe is a few pixels long: no name is drawn
        assert full["pipes"] == 2 * 30 * 29 + 1
        assert full["pipeLabels"] == 0 and full["meterLabels"] == 0
        canvas = browser.find_element("id", "map")
        frames = full["frames"]
        ActionChains(browser).scroll_from_origin(
            ScrollOrigin.from_element(canvas), 0, -1200
        ).perform()
        zoomed = wait_for(
            lambda: (s := page_state(browser))["frames"] > frames and s["pipeLabels"] and s,
            "the pipes' names once zoomed in",
        )
        scale = browser.execute_script("return view.s * net.typical")
        assert scale >= 70  # LABEL_PX.pipe: a pipe this long on screen has room for its name
        # only the pipes on screen are named
        assert 0 < zoomed["pipeLabels"] < full["pipes"]
        assert zoomed["meterLabels"] == 2  # and the meters' names
    finally:
        server.stop()


def test_while_the_answer_waits_the_early_region_and_its_due_time_are_shown(
    browser: Any,  # noqa: F811
    config: tuple[Calibration, Path],  # noqa: F811
    feed: list[str],  # noqa: F811
    tmp_path: Path,
) -> None:
    """A real monitor with a classifier gives the arrivals' answer at once (a transient record)
    and waits for the lasting drop; fed up to half the wait, the page shows the early region
    and when the answer is due, not a bare "locating"."""
    from burstloc.localize.classify import ClassifierConfig

    classifier = ClassifierConfig(max_residual=1.0, min_scale=0.0, rise_tolerance=0.05)
    path = classifier.save(tmp_path / "classifier.json")
    delays = config[0].for_interval(0.2)
    half = int(delays.decision_delay / 2 / 0.2)  # steps: half the signature's wait
    assert delays.arrival_decision_delay < delays.decision_delay / 2
    m = Monitor(PAPER15, config[1], "--web", "127.0.0.1:0", "--classify", str(path))
    try:
        m.feed(feed[: (ONSET_STEPS + half) * len(METERS)])
        early = m.record("transient")
        browser.get(m.url)
        state = wait_for(
            lambda: (s := page_state(browser)).get("transient") and s.get("region") and s,
            "the early record on the page",
        )
        assert state["answer"] is None and state["transient"]["time"] == early["time"]
        drawn = [(r["pipe"], r["low"], r["high"]) for r in state["region"]["stretches"]]
        assert drawn == [(r["pipe"], r["low"], r["high"]) for r in early["region"]["stretches"]]
        onset = early["answer_at"] - early["wait_s"]
        assert onset <= early["first_alarm"] < early["answer_at"]
        due = f"DUE AT T = {early['answer_at']:.1f} S"
        # counted down in reading time: once the page has every reading fed (they stream in,
        # later on a loaded machine), the last one is half the wait in
        last = float(feed[(ONSET_STEPS + half) * len(METERS) - 1].split(",")[0])
        left = early["answer_at"] - last
        assert left > 0
        count = f"IN {math.floor(left + 0.5)} S"
        text = wait_for(
            lambda: (
                (t := browser.find_element("id", "answer").text.upper())
                and due in t
                and count in t
                and t
            ),
            "the panel says when the answer is due, counted from the last reading",
        )
        assert f"ONSET T = {onset:.1f} S + THE {math.floor(early['wait_s'] + 0.5)} S WAIT" in text
        assert "LOCATING" not in text and f"PIPE {early['pipes'][0]['pipe']}" in text
    finally:
        m.stop()
