"""The page's incident routes over real HTTP (the server as ``burstloc monitor --web --db``
runs it, on a real store): writes need the token even on loopback, are refused from another
site, are recorded with who and when; reads come from the store."""

from __future__ import annotations

import json
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from burstloc.incidents import IncidentStore
from burstloc.incidents.intake import from_record
from burstloc.web import control_room
from burstloc.web.incidents import CSRF_HEADER

ROOT = Path(__file__).resolve().parents[2]
PAPER15 = ROOT / "networks" / "paper15.inp"
TOKEN = "t0ken-for-tests"
RECORD = {
    "type": "decision", "burst": True, "first_alarm": 62.4, "time": 75.0,
    "pipes": [{"pipe": "9", "score": 0.0}], "region": {"length_m": 80.0},
}  # fmt: skip


@pytest.fixture
def store(tmp_path: Path) -> Iterator[IncidentStore]:
    opened = IncidentStore.open(str(tmp_path / "incidents.sqlite"))
    item = from_record(RECORD, time.time())
    assert item is not None
    opened.take([item])
    yield opened
    opened.close()


def _server(store: IncidentStore | None, token: str | None) -> Any:
    server = control_room(PAPER15, ["N3"], 0.2, token=token, incidents=store)
    server.start()
    return server


def _request(
    url: str, method: str = "GET", body: Any = None, headers: dict[str, str] | None = None
) -> tuple[int, Any]:
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(url, data=data, method=method, headers=headers or {})
    try:
        with urllib.request.urlopen(request, timeout=30) as response:
            return response.status, json.loads(response.read())
    except urllib.error.HTTPError as exc:
        text = exc.read()
        try:
            return exc.code, json.loads(text)
        except ValueError:
            return exc.code, text.decode()


def _write_headers(**extra: str) -> dict[str, str]:
    return {
        "Authorization": f"Bearer {TOKEN}",
        "Content-Type": "application/json",
        CSRF_HEADER: "page",
        **extra,
    }


def test_without_a_token_writes_are_refused_even_on_loopback(store: IncidentStore) -> None:
    server = _server(store, None)
    try:
        base = f"http://127.0.0.1:{server.port}"
        status, doc = _request(f"{base}/incidents.json")
        assert status == 200 and doc["enabled"] and not doc["writable"]
        assert "--web-token" in doc["why"]
        (row,) = doc["incidents"]
        status, doc = _request(
            f"{base}/incidents/{row['id']}/acknowledge", "POST", {"by": "ann"},
            {"Content-Type": "application/json", CSRF_HEADER: "page"},
        )  # fmt: skip
        assert status == 403 and "needs a token" in doc["error"] and "--web-token" in doc["error"]
        assert store.get(row["id"])["state"] == "detected"
    finally:
        server.stop()


def test_writes_need_the_token_and_come_from_the_page_itself(store: IncidentStore) -> None:
    server = _server(store, TOKEN)
    try:
        base = f"http://127.0.0.1:{server.port}"
        (row,) = store.incidents()
        url = f"{base}/incidents/{row['id']}/acknowledge"
        own = f"http://127.0.0.1:{server.port}"
        refusals = [
            ({"Authorization": "Bearer wrong"}, 401, "unauthorized"),
            ({"Authorization": ""}, 401, "unauthorized"),
            ({"Sec-Fetch-Site": "cross-site"}, 403, "cross-site request refused"),
            ({"Sec-Fetch-Site": "same-site"}, 403, "cross-site request refused"),
            ({"Origin": "http://evil.example"}, 403, "Origin http://evil.example"),
            ({CSRF_HEADER: ""}, 403, f"header {CSRF_HEADER} is missing"),
            ({"Content-Type": "text/plain"}, 415, "must be JSON"),
        ]
        for extra, status, message in refusals:
            got, doc = _request(url, "POST", {"by": "mallory"}, _write_headers(**extra))
            assert got == status, (extra, doc)
            assert message in (doc if isinstance(doc, str) else doc["error"]), (extra, doc)
        assert store.get(row["id"])["state"] == "detected"  # nothing got through
        # the page's own request: same origin, the header, the token
        got, doc = _request(
            url, "POST", {"by": "ann", "note": "seen"},
            _write_headers(**{"Origin": own, "Sec-Fetch-Site": "same-origin"}),
        )  # fmt: skip
        assert got == 200 and doc["state"] == "acknowledged"
        last = doc["history"][-1]
        assert (last["action"], last["by"], last["via"], last["note"]) == (
            "acknowledged", "ann", "page 127.0.0.1", "seen",
        )  # fmt: skip
        assert abs(last["at"] - time.time()) < 3600  # a wall-clock time, recorded by the server
    finally:
        server.stop()


def test_the_life_cycle_through_the_routes_and_its_refusals(store: IncidentStore) -> None:
    server = _server(store, TOKEN)
    try:
        base = f"http://127.0.0.1:{server.port}"
        (row,) = store.incidents()
        n = row["id"]

        def post(action: str, body: dict[str, Any]) -> tuple[int, Any]:
            return _request(f"{base}/incidents/{n}/{action}", "POST", body, _write_headers())

        assert post("dispatch", {"by": "ann"})[0] == 409  # not acknowledged yet
        assert post("acknowledge", {})[1]["error"].startswith("the operator's name is required")
        assert post("acknowledge", {"by": "ann"})[0] == 200
        assert post("dispatch", {"by": "ann", "note": "crew 3"})[0] == 200
        status, doc = post("close", {"by": "bob", "outcome": "found"})
        assert status == 400 and "at = [x, y]" in doc["error"]
        status, doc = post("close", {"by": "bob", "outcome": "found", "at": [12.5, 40.0]})
        assert status == 200 and doc["state"] == "closed" and doc["found_x"] == 12.5
        status, doc = post("acknowledge", {"by": "carol"})
        assert status == 409 and f"incident {n} is closed" in doc["error"]
        assert _request(f"{base}/incidents/999/acknowledge", "POST", {"by": "a"},
                        _write_headers())[0] == 404  # fmt: skip
        assert post("archive", {"by": "ann"})[0] == 404
        status, listed = _request(
            f"{base}/incidents.json", headers={"Authorization": f"Bearer {TOKEN}"}
        )
        assert status == 200 and listed["incidents"][0]["state"] == "closed"
        version = listed["version"]
        status, same = _request(
            f"{base}/incidents.json?after={version}", headers={"Authorization": f"Bearer {TOKEN}"}
        )
        assert same == {"enabled": True, "version": version, "unchanged": True}
        status, one = _request(f"{base}/incidents/{n}.json?token={TOKEN}")
        assert [h["action"] for h in one["history"]] == [
            "detected", "acknowledged", "dispatched", "closed",
        ]  # fmt: skip
        # the other methods stay refused, and so do writes anywhere else
        assert _request(f"{base}/state.json", "POST", {}, _write_headers())[0] == 405
    finally:
        server.stop()


def test_the_list_counts_each_meters_false_alarms(tmp_path: Path) -> None:
    opened = IncidentStore.open(str(tmp_path / "incidents.sqlite"))
    for first, alarmed in [(62.4, ["N3", "N7"]), (900.0, ["N7", "N9"])]:
        item = from_record({**RECORD, "first_alarm": first, "alarmed": alarmed}, time.time())
        assert item is not None
        opened.take([item])
    server = _server(opened, TOKEN)
    try:
        base = f"http://127.0.0.1:{server.port}"
        status, doc = _request(f"{base}/incidents.json", headers=_write_headers())
        assert status == 200
        assert {m["meter"]: m["false_alarms"] for m in doc["meters"]} == {"N3": 0, "N7": 0, "N9": 0}
        first = next(r["id"] for r in doc["incidents"] if r["alarmed"] == ["N3", "N7"])
        for action, body in [
            ("acknowledge", {"by": "ann"}),
            ("close", {"by": "ann", "outcome": "false-alarm"}),
        ]:
            status, _ = _request(
                f"{base}/incidents/{first}/{action}", "POST", body, _write_headers()
            )
            assert status == 200
        status, doc = _request(f"{base}/incidents.json", headers=_write_headers())
        meters = {m["meter"]: m for m in doc["meters"]}
        assert [m["meter"] for m in doc["meters"]] == ["N3", "N7", "N9"]  # most false alarms first
        assert (meters["N7"]["false_alarms"], meters["N7"]["alarmed"]) == (1, 2)
        assert meters["N7"]["false_alarm_incidents"] == [first]
        assert (meters["N9"]["false_alarms"], meters["N9"]["alarmed"]) == (0, 1)
    finally:
        server.stop()
        opened.close()


def test_without_a_store_the_page_says_incidents_are_not_kept() -> None:
    server = _server(None, TOKEN)
    try:
        base = f"http://127.0.0.1:{server.port}"
        status, doc = _request(f"{base}/incidents.json?token={TOKEN}")
        assert status == 200 and doc["enabled"] is False and "--db" in doc["why"]
        status, doc = _request(f"{base}/incidents/1/acknowledge", "POST", {"by": "a"},
                               _write_headers())  # fmt: skip
        assert status == 404 and "--db" in doc["error"]
    finally:
        server.stop()


def test_shelving_through_the_routes_needs_the_token_and_the_page_itself(
    store: IncidentStore,
) -> None:
    server = _server(store, TOKEN)
    try:
        base = f"http://127.0.0.1:{server.port}"
        (row,) = store.incidents()
        n = row["id"]
        url = f"{base}/incidents/{n}/shelve"
        body = {"by": "mallory", "for": "30m", "reason": "hide it"}
        for extra, status in [
            ({"Authorization": "Bearer wrong"}, 401),
            ({"Sec-Fetch-Site": "cross-site"}, 403),
            ({"Origin": "http://evil.example"}, 403),
            ({CSRF_HEADER: ""}, 403),
        ]:
            assert _request(url, "POST", body, _write_headers(**extra))[0] == status, extra
        meter = f"{base}/incidents/meters/N3/shelve"
        assert _request(meter, "POST", body, _write_headers(Origin="http://evil.example"))[0] == 403
        assert store.get(n)["shelved_until"] is None and store.shelves.meters() == {}

        def post(path: str, payload: dict[str, Any]) -> tuple[int, Any]:
            return _request(f"{base}/{path}", "POST", payload, _write_headers())

        status, doc = post(f"incidents/{n}/shelve", {"by": "ann", "for": "30m"})
        assert status == 400 and "shelving needs a reason" in doc["error"]
        status, doc = post(f"incidents/{n}/shelve", {"by": "ann", "for": "3d", "reason": "r"})
        assert status == 400 and "at most 24 h" in doc["error"] and "'3d'" in doc["error"]
        status, doc = post(f"incidents/{n}/shelve", {"by": "ann", "reason": "r"})
        assert status == 400 and "a number with a unit" in doc["error"]
        status, doc = post(f"incidents/{n}/shelve", {"by": "ann", "for": "2h", "reason": "works"})
        assert status == 200 and doc["shelved_by"] == "ann" and doc["shelved_reason"] == "works"
        assert 7100 < doc["shelved_until"] - time.time() <= 7200
        last = doc["history"][-1]
        assert (last["action"], last["by"], last["via"], last["note"]) == (
            "shelved", "ann", "page 127.0.0.1", "works",
        )  # fmt: skip
        status, listed = _request(f"{base}/incidents.json", headers=_write_headers())
        assert listed["incidents"][0]["shelved_until"] == doc["shelved_until"]
        status, doc = post(f"incidents/{n}/unshelve", {"by": "bob"})
        assert status == 200 and doc["shelved_until"] is None
        status, doc = post(f"incidents/{n}/unshelve", {"by": "bob"})
        assert status == 409 and "cannot be unshelved" in doc["error"]

        status, doc = post(
            "incidents/meters/N3/shelve", {"by": "ann", "for": "4h", "reason": "recal"}
        )
        assert status == 200 and doc["reason"] == "recal"
        status, listed = _request(f"{base}/incidents.json", headers=_write_headers())
        assert list(listed["shelved_meters"]) == ["N3"]
        assert listed["shelved_meters"]["N3"]["by"] == "ann"
        assert post("incidents/meters/N3/unshelve", {"by": "ann"})[0] == 200
        status, doc = post("incidents/meters/N3/unshelve", {"by": "ann"})
        assert status == 400 and "not shelved" in doc["error"]
        assert post("incidents/meters/N3/archive", {"by": "ann"})[0] == 404
    finally:
        server.stop()
