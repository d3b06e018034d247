"""The page's incident routes: the list and one incident from the store, and the operators'
actions on them.

Reads (GET): ``/incidents.json`` (every incident, open first, and per meter the incidents its
alarms made and how many were closed as false alarms:
:func:`~burstloc.incidents.outcomes.meter_outcomes`; ``?after=VERSION`` answers
``{"unchanged": true}`` when nothing changed since the version the page has, so that polling
costs one indexed query) and ``/incidents/{id}.json`` (one incident with its record and
history). They are read from the store, not the monitor's memory: after a restart the page
shows the same incidents.

Writes (POST ``/incidents/{id}/{action}``, action ``acknowledge``, ``dispatch``, ``close``,
``note``, ``shelve`` or ``unshelve``; a JSON body ``{"by": NAME, "note": TEXT, "outcome":
"found" | "false-alarm", "at": [X, Y], "for": "30m", "reason": TEXT}``; and POST
``/incidents/meters/{meter}/shelve`` or ``/unshelve``, the listing's ``shelved_meters``:
:mod:`burstloc.incidents.shelving`) are refused, before the store is touched:

* with 403 when the server has no token, even on a loopback address (anyone on the machine
  could act in an operator's name): the message says to set ``--web-token``; a wrong or missing
  token is refused with 401 before any route (:mod:`burstloc.web.server`);
* with 403 when the request comes from another site: ``Sec-Fetch-Site`` other than
  ``same-origin`` (or ``none``), an ``Origin`` other than the page's own, or no
  :data:`CSRF_HEADER` header (a custom header no form can send, and which a page of another
  site cannot send without a CORS preflight this server never grants);
* with 415 for a body that is not JSON; 400 for a bad one (no operator name, a found outcome
  without a point); 404 for an unknown incident; 409 for an action its state does not allow.

Each accepted write is recorded with the operator's name, the time and ``page ADDRESS``
(:meth:`burstloc.incidents.store.IncidentStore.act`). The store's calls run on worker threads:
the page's event loop (which pushes the monitor's news) never waits for a database.
"""

from __future__ import annotations

import asyncio
import json
import time
from typing import Any

from burstloc.exceptions import InputError
from burstloc.incidents.errors import (
    IncidentStateError,
    IncidentStoreError,
    UnknownIncidentError,
)
from burstloc.incidents.lifecycle import ACTIONS, FALSE_ALARM, FOUND, Outcome
from burstloc.incidents.outcomes import meter_outcomes
from burstloc.incidents.shelving import parse_duration

__all__ = ["CSRF_HEADER", "NOT_KEPT", "NO_TOKEN", "routes", "write_refusal"]

#: The header every write must carry (its value: anything non-empty).
CSRF_HEADER = "X-Burstloc-Request"
#: Said when the monitor keeps no incidents.
NOT_KEPT = "incidents are not kept: start the monitor with --db to keep them"
#: Said when a write comes to a server without a token.
NO_TOKEN = (
    "acting on incidents needs a token, even on this machine's own address: start the monitor "
    "with --web-token TOKEN (or the environment variable BURSTLOC_WEB_TOKEN) and open the page "
    "with ?token=TOKEN"
)
_MOST_BODY = 64 * 1024
#: The shelving actions, on an incident and on a meter.
_SHELVING = ("shelve", "unshelve")


def write_refusal(headers: Any, own_origin: str, token: str | None) -> str | None:
    """Why a write with ``headers`` is refused (module docstring), or ``None``."""
    if token is None:
        return NO_TOKEN
    site = headers.get("sec-fetch-site")
    if site is not None and site not in ("same-origin", "none"):
        return f"cross-site request refused (Sec-Fetch-Site: {site})"
    origin = headers.get("origin")
    if origin is not None and origin != own_origin:
        return f"cross-site request refused (Origin {origin}, not {own_origin})"
    if not headers.get(CSRF_HEADER.lower()):
        return f"request refused: the header {CSRF_HEADER} is missing (the page sends it)"
    return None


def _outcome(body: dict[str, Any]) -> Outcome:
    kind = body.get("outcome")
    if kind == FALSE_ALARM:
        return Outcome.false_alarm()
    if kind == FOUND:
        at = body.get("at")
        if not (isinstance(at, list) and len(at) == 2 and all(_number(v) for v in at)):
            raise InputError("a found outcome needs the point where it was found: at = [x, y]")
        return Outcome.found(float(at[0]), float(at[1]))
    raise InputError(f"outcome must be {FOUND!r} or {FALSE_ALARM!r}, got {kind!r}")


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _text(body: dict[str, Any], key: str) -> str | None:
    value = body.get(key)
    if value is not None and not isinstance(value, str):
        raise InputError(f"{key!r} must be text, got {type(value).__name__}")
    return value


def routes(server: Any) -> list[Any]:
    """The incident routes of ``server`` (a :class:`~burstloc.web.server.WebServer`; its
    ``incidents`` store may be ``None``: the list then says incidents are not kept)."""
    from starlette.responses import JSONResponse
    from starlette.routing import Route

    def error(status: int, message: str) -> Any:
        return JSONResponse({"error": message}, status_code=status)

    async def listing(request: Any) -> Any:
        store = server.incidents
        if store is None:
            return JSONResponse({"enabled": False, "why": NOT_KEPT})
        try:
            version = await asyncio.to_thread(store.version)
            after = request.query_params.get("after")
            if after is not None and after == str(version):
                return JSONResponse({"enabled": True, "version": version, "unchanged": True})
            rows = await asyncio.to_thread(store.incidents)
            shelved = await asyncio.to_thread(store.shelves.meters)
        except IncidentStoreError as exc:
            return error(503, str(exc))
        doc = {
            "enabled": True,
            "writable": server.token is not None,
            "why": None if server.token is not None else NO_TOKEN,
            "version": version,
            "now": time.time(),
            "incidents": rows,
            "meters": [m.to_json() for m in meter_outcomes(rows)],
            "shelved_meters": shelved,
        }
        return JSONResponse(doc)

    async def one(request: Any) -> Any:
        if server.incidents is None:
            return error(404, NOT_KEPT)
        try:
            number = int(request.path_params["id"])
            return JSONResponse(await asyncio.to_thread(server.incidents.get, number))
        except ValueError:
            return error(404, f"no incident {request.path_params['id']!r}")
        except UnknownIncidentError as exc:
            return error(404, str(exc))
        except IncidentStoreError as exc:
            return error(503, str(exc))

    async def guarded(request: Any) -> Any:
        """The JSON body of a write (a dict), or the response refusing it."""
        if server.incidents is None:
            return error(404, NOT_KEPT)
        own = f"{request.url.scheme}://{request.headers.get('host', '')}"
        refused = write_refusal(request.headers, own, server.token)
        if refused is not None:
            return error(403, refused)
        if request.headers.get("content-type", "").split(";")[0].strip() != "application/json":
            return error(415, "the body must be JSON (Content-Type: application/json)")
        raw = await request.body()
        try:
            if len(raw) > _MOST_BODY:
                raise InputError(f"the body is longer than {_MOST_BODY} bytes")
            body = json.loads(raw or b"{}")
            if not isinstance(body, dict):
                raise InputError("the body must be a JSON object")
        except (InputError, ValueError) as exc:  # json's errors are ValueErrors
            return error(400, str(exc))
        return body

    async def answer(call: Any, *args: Any, **kwargs: Any) -> Any:
        """``call`` on a worker thread, its errors as the HTTP statuses of the module docstring."""
        try:
            return JSONResponse(await asyncio.to_thread(call, *args, **kwargs))
        except UnknownIncidentError as exc:
            return error(404, str(exc))
        except IncidentStateError as exc:
            return error(409, str(exc))
        except IncidentStoreError as exc:
            return error(503, str(exc))
        except (InputError, ValueError) as exc:
            return error(400, str(exc))

    async def act(request: Any) -> Any:
        action = request.path_params["action"]
        if action not in ACTIONS and action not in _SHELVING:
            known = ", ".join((*ACTIONS, *_SHELVING))
            return error(404, f"no action {action!r}: one of {known}")
        body = await guarded(request)
        if not isinstance(body, dict):
            return body
        store = server.incidents
        client = request.client.host if request.client else "?"
        try:
            number = int(request.path_params["id"])
            by, note = _text(body, "by") or "", _text(body, "note")
            if action == "shelve":
                seconds = parse_duration(_text(body, "for") or "")
                reason = _text(body, "reason") or ""
                return await answer(
                    store.shelves.shelve, number, seconds, by=by, via=f"page {client}",
                    reason=reason,
                )  # fmt: skip
            if action == "unshelve":
                return await answer(
                    store.shelves.unshelve, number, by=by, via=f"page {client}", note=note
                )
            outcome = _outcome(body) if action == "close" else None
        except (InputError, ValueError) as exc:
            return error(400, str(exc))
        return await answer(
            store.act, number, action, by=by, via=f"page {client}", note=note, outcome=outcome
        )

    async def meter(request: Any) -> Any:
        action = request.path_params["action"]
        if action not in _SHELVING:
            return error(404, f"no action {action!r} on a meter: one of {', '.join(_SHELVING)}")
        body = await guarded(request)
        if not isinstance(body, dict):
            return body
        shelves = server.incidents.shelves
        name, client = request.path_params["meter"], request.client.host if request.client else "?"
        try:
            by = _text(body, "by") or ""
            if action == "unshelve":
                return await answer(shelves.unshelve_meter, name, by=by, via=f"page {client}")
            seconds = parse_duration(_text(body, "for") or "")
            reason = _text(body, "reason") or ""
        except (InputError, ValueError) as exc:
            return error(400, str(exc))
        return await answer(
            shelves.shelve_meter, name, seconds, by=by, via=f"page {client}", reason=reason
        )

    return [
        Route("/incidents.json", listing),
        Route("/incidents/{id}.json", one),
        Route("/incidents/{id}/{action}", act, methods=["POST"]),
        Route("/incidents/meters/{meter:path}/{action}", meter, methods=["POST"]),
    ]
