"""The control-room page's incidents in a real browser (Debian's Chromium) over a real monitor
process keeping a real burst in a real store: an operator acknowledges, dispatches and closes it
(found at a point clicked on the map); after the monitor restarts on the same store, the page
shows the same incident and history, and the Meters table each alarmed meter's false alarms."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from test_control_room import PAPER15, browser, config, feed  # noqa: F401 (fixtures)
from web_browser import Monitor, page_state, wait_for

from burstloc.localize.config import Calibration

TOKEN = "operator-t0ken"


def _open(driver: Any, monitor: Monitor) -> dict[str, Any]:
    driver.get(monitor.url.split("?")[0] + f"?token={TOKEN}")
    return wait_for(
        lambda: (i := page_state(driver).get("incidents") or {}).get("detail") and i,
        "the page shows an incident from the store",
    )


def _click(driver: Any, button: str) -> None:
    """Click ``button`` once the page has enabled it (the state it follows is shown)."""
    wait_for(lambda: driver.find_element("id", button).is_enabled(), f"{button} enabled")
    driver.find_element("id", button).click()


def _state(driver: Any) -> dict[str, Any]:
    return page_state(driver)["incidents"]


@pytest.mark.parametrize("backend", ["sqlite", "postgresql"])
def test_an_operator_acts_on_an_incident_and_the_page_remembers_it_after_a_restart(
    browser: Any,  # noqa: F811
    config: tuple[Calibration, Path],  # noqa: F811
    feed: list[str],  # noqa: F811
    tmp_path: Path,
    backend: str,
    request: pytest.FixtureRequest,
) -> None:
    from selenium.webdriver.common.action_chains import ActionChains

    if backend == "sqlite":
        db = str(tmp_path / "incidents.sqlite")
    else:
        db = request.getfixturevalue("postgresql").database()
    options = ("--web", "127.0.0.1:0", "--web-token", TOKEN, "--db", db)
    first = Monitor(PAPER15, config[1], *options)
    try:
        first.feed(feed)
        record = first.record("decision")
        pipe = record["pipes"][0]["pipe"]
        incidents = _open(browser, first)
        wait_for(
            lambda: (d := _state(browser)["detail"]) and d["kind"] == "burst",
            "the located burst is the incident shown",
        )
        incidents = _state(browser)
        assert incidents["writable"] and incidents["detail"]["pipe"] == pipe
        assert incidents["detail"]["state"] == "detected"
        row = browser.find_element("css selector", f"#inclist tr[data-i='{incidents['selected']}']")
        assert "DETECTED" in row.text.upper() and f"pipe {pipe}" in row.text
        browser.find_element("id", "op-name").send_keys("ann")
        # shelved for a while with a reason: listed apart, then brought back
        browser.find_element("id", "op-reason").send_keys("valve exercise nearby")
        _click(browser, "b-shelve")
        shelved = wait_for(
            lambda: (d := _state(browser)["detail"])["shelved_until"] and d, "shelved"
        )
        assert shelved["history"][-1]["action"] == "shelved"
        assert shelved["shelved_until"] - shelved["history"][-1]["at"] == 1800.0  # 30 min
        assert shelved["shelved_reason"] == "valve exercise nearby"
        wait_for(
            lambda: browser.find_elements("css selector", "#shelvedgroup ~ tr.shelved"),
            "the list shows it in the shelved group",
        )
        assert "shelved until" in browser.find_element("id", "incdetail").text
        _click(browser, "b-unshelve")
        wait_for(lambda: _state(browser)["detail"]["shelved_until"] is None, "unshelved")
        wait_for(lambda: not browser.find_elements("id", "shelvedgroup"), "the list shows it back")
        browser.find_element("id", "op-note").send_keys("seen on the map")
        _click(browser, "b-ack")
        wait_for(lambda: _state(browser)["detail"]["state"] == "acknowledged", "acknowledged")
        _click(browser, "b-dispatch")
        wait_for(lambda: _state(browser)["detail"]["state"] == "dispatched", "dispatched")
        # close: found at a point clicked on the map (on the named pipe's first node)
        browser.find_element("id", "op-note").send_keys("found under the road")
        _click(browser, "b-found")
        wait_for(lambda: _state(browser)["picking"], "the page waits for a click on the map")
        where = browser.execute_script(
            "const i = net.linkIndex[arguments[0]], n = net.links.from[i];"
            "const r = map.getBoundingClientRect();"
            "return {x: net.nodes.x[n], y: net.nodes.y[n], px: sx(net.nodes.x[n]),"
            " py: sy(net.nodes.y[n]), w: r.width, h: r.height, s: view.s};",
            pipe,
        )
        canvas = browser.find_element("id", "map")
        dx, dy = round(where["px"] - where["w"] / 2), round(where["py"] - where["h"] / 2)
        ActionChains(browser).move_to_element_with_offset(canvas, dx, dy).click().perform()
        closed = wait_for(
            lambda: (d := _state(browser)["detail"])["state"] == "closed" and d, "closed"
        )
        assert closed["outcome"] == "found"
        pixel = 1.5 / where["s"]  # the click lands on a whole pixel
        assert abs(closed["found_x"] - where["x"]) <= pixel
        assert abs(closed["found_y"] - where["y"]) <= pixel
        history = [(h["action"], h["by"], h["note"]) for h in closed["history"]]
        assert history[-3:] == [
            ("acknowledged", "ann", "seen on the map"),
            ("dispatched", "ann", None),
            ("closed", "ann", "found under the road"),
        ]
        assert all(h["via"] == "page 127.0.0.1" for h in closed["history"][-3:])
        wait_for(
            lambda: "found at" in browser.find_element("id", "incdetail").text,
            "the panel says where it was found",
        )
    finally:
        first.stop()
    second = Monitor(PAPER15, config[1], *options)  # a restart, on the same store
    try:
        _open(browser, second)
        browser.find_element("css selector", f"#inclist tr[data-i='{closed['id']}']").click()
        again = wait_for(
            lambda: (d := _state(browser)["detail"]) and d["id"] == closed["id"] and d,
            "the same incident after the restart",
        )
        assert again["history"] == closed["history"]
        assert (again["state"], again["found_x"], again["found_y"]) == (
            "closed", closed["found_x"], closed["found_y"],
        )  # fmt: skip
        # and the operator's buttons follow the state: nothing but a note on a closed incident
        buttons = {b: browser.find_element("id", b).is_enabled() for b in
                   ("b-ack", "b-dispatch", "b-found", "b-false", "b-note", "b-shelve",
                    "b-unshelve")}  # fmt: skip
        assert buttons == {
            "b-ack": False, "b-dispatch": False, "b-found": False, "b-false": False,
            "b-note": True, "b-shelve": False, "b-unshelve": False,
        }  # fmt: skip
        # the Meters table: each alarmed meter's false alarms of the incidents it alarmed in
        alarmed = set(record["alarmed"])

        def cells() -> dict[str, tuple[str, str]]:
            # read in one go in the page: the table is redrawn with each health record
            read = browser.execute_script(
                "const out = {};"
                "for (const tr of document.querySelectorAll('#health tbody tr')) {"
                "  const td = tr.querySelector('td.fa');"
                "  if (td) out[tr.dataset.m] = [td.innerText.trim(), td.title || ''];"
                "}"
                "return out;"
            )
            return {m: (text, title) for m, (text, title) in read.items()}

        shown = wait_for(
            lambda: (c := cells()) and all(c.get(m, ("",))[0] == "0/1" for m in alarmed) and c,
            "the alarmed meters' false alarms in the Meters table",
        )
        assert {m for m, (text, _) in shown.items() if text} == alarmed
        assert all(f"#{closed['id']}" in shown[m][1] for m in alarmed)
    finally:
        second.stop()


def test_a_link_to_an_incident_opens_that_incident(
    browser: Any,  # noqa: F811
    tmp_path: Path,
) -> None:
    """The link of a webhook alert (``#incident=ID``) selects that incident, not the newest."""
    from burstloc.incidents import IncidentStore
    from burstloc.incidents.intake import from_record
    from burstloc.web import control_room

    store = IncidentStore.open(str(tmp_path / "incidents.sqlite"))
    for k in (1, 2):
        record = {"type": "decision", "first_alarm": 10.0 * k, "time": 10.0 * k + 1,
                  "pipes": [{"pipe": "9", "score": 0.0}]}  # fmt: skip
        item = from_record(record, 1.8e9 + k)
        assert item is not None
        store.take([item])
    server = control_room(PAPER15, ["N3"], 0.2, token=TOKEN, incidents=store)
    server.start()
    page = server.url.split("?")[0] + f"?token={TOKEN}"
    try:
        for link, shown in ((f"{page}#incident=1", 1), (page, 2)):  # by default: the newest
            browser.get("about:blank")
            browser.get(link)
            got = wait_for(
                lambda: (i := page_state(browser).get("incidents") or {}).get("detail") and i,
                "the page shows an incident",
            )
            assert got["selected"] == shown and got["detail"]["id"] == shown
    finally:
        server.stop()
        store.close()
