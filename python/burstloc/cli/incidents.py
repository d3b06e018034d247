"""``burstloc incidents``: list, show and export the incidents the monitor kept, and act on
them (acknowledge, dispatch, close with an outcome, add a note; shelve, in
:mod:`burstloc.cli.shelving`) without the page; what closed
incidents teach: false alarms per meter (``meters``) and the bursts found as a known-events file
for calibration (``known-events``)."""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any

from burstloc.cli._incidents import stamp
from burstloc.cli.shelving import SHELVING
from burstloc.cli.shelving import add_parsers as add_shelving
from burstloc.exceptions import ConfigError

__all__ = ["DB_VARIABLE", "add_parser", "age", "open_store", "run"]

#: The environment variable naming the store when neither --db nor --state does.
DB_VARIABLE = "BURSTLOC_DB"

_ACTIONS = {"ack": "acknowledge", "dispatch": "dispatch", "close": "close", "note": "note"}


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc incidents``."""
    where = argparse.ArgumentParser(add_help=False)
    group = where.add_argument_group("the store")
    group.add_argument(
        "--db",
        metavar="PATH|URL",
        help="the incident store: an SQLite file or a postgresql:// URL (default: the "
        f"environment variable {DB_VARIABLE})",
    )
    group.add_argument(
        "--state", metavar="FILE", help="or the monitor's state file: its store is beside it"
    )
    parser = subparsers.add_parser(
        "incidents",
        help="the monitor's incidents: list, show, export, picture; acknowledge, dispatch, close; "
        "false alarms per meter; found bursts as known events",
        description=(
            "The incidents kept by `burstloc monitor --db` (every located burst, early alarm "
            "record, event and meter fault, with its history). An incident is detected, then "
            "acknowledged, possibly dispatched, and closed with an outcome: found at a point "
            "(X,Y in the network's coordinates) or a false alarm. An open incident may be "
            "shelved for a while with a reason (not escalated meanwhile; it comes back by "
            "itself), and a meter's faults too. Each action is recorded with who (--by) and "
            "when."
        ),
    )
    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")
    listing = actions.add_parser("list", parents=[where], help="open incidents first, with age")
    listing.add_argument("--open", action="store_true", help="only the open incidents")
    listing.add_argument("--limit", type=int, metavar="N", help="at most N incidents")
    show = actions.add_parser("show", parents=[where], help="one incident and its history")
    show.add_argument("id", type=int, metavar="ID")
    export = actions.add_parser("export", parents=[where], help="every incident, CSV or JSON")
    export.add_argument("--format", choices=("csv", "json"), default="csv")
    export.add_argument("--out", metavar="FILE", help="write here (default: stdout)")
    meters = actions.add_parser(
        "meters",
        parents=[where],
        help="per meter: the incidents its alarms made and how many were false alarms",
        description="Each meter whose alarms made an incident: how many incidents, how many "
        "of them were closed as false alarms and how many as found, and their numbers (most "
        "false alarms first).",
    )
    meters.add_argument("--format", choices=("table", "csv", "json"), default="table")
    meters.add_argument("--out", metavar="FILE", help="write here (default: stdout)")
    known = actions.add_parser(
        "known-events",
        parents=[where],
        help="the bursts found, as a known-events file for `burstloc calibrate --known-events`",
        description="Every incident closed as found, as a known event: the found point snapped "
        "to the nearest pipe (and its position along it), the time the first alarmed meter's "
        "change began and the readings the monitor kept around the alarm. Each found incident "
        "that cannot become an event is named on stderr with the reason.",
    )
    known.add_argument(
        "--network", required=True, metavar="NETWORK.inp", help="the network the monitor watched"
    )
    known.add_argument("--out", required=True, metavar="FILE.json", help="write the file here")
    known.add_argument(
        "--within",
        type=float,
        default=None,
        metavar="D",
        help="the farthest a found point may be from the nearest pipe, in the network's "
        "coordinates (default: 50)",
    )
    png = actions.add_parser(
        "png",
        parents=[where],
        help="a picture for the work order: the incident's map and panel as PNG",
        description="Draw the incident as the control-room page shows it (the map around its "
        "search region, the named pipe, the pipes' names; where, how sure, its state and "
        "history) and write it as PNG, with headless Chromium (apt-get install chromium).",
    )
    png.add_argument("id", type=int, metavar="ID")
    png.add_argument(
        "--network", required=True, metavar="NETWORK.inp", help="the network the monitor watched"
    )
    png.add_argument("--out", required=True, metavar="FILE.png", help="write the picture here")
    png.add_argument(
        "--size", default="1400x900", metavar="WxH", help="in pixels (default: 1400x900)"
    )
    for name, text in [
        ("ack", "acknowledge an incident (it has been seen)"),
        ("dispatch", "a crew is sent (after the acknowledgement)"),
        ("close", "close with an outcome: --found X,Y or --false-alarm"),
        ("note", "add a note (any state)"),
    ]:
        act = actions.add_parser(name, parents=[where], help=text)
        act.add_argument("id", type=int, metavar="ID")
        act.add_argument("--by", required=True, metavar="NAME", help="who acts (recorded)")
        act.add_argument("--note", metavar="TEXT", required=name == "note", help="a note")
        if name == "close":
            outcome = act.add_mutually_exclusive_group(required=True)
            outcome.add_argument(
                "--found", metavar="X,Y", help="found at this point (network coordinates)"
            )
            outcome.add_argument("--false-alarm", action="store_true", help="a false alarm")
    add_shelving(actions, where)
    parser.set_defaults(handler=run)
    return parser


def open_store(db: str | None, state: str | None) -> Any:
    """The store named by ``db`` (or the environment) or beside ``state``.

    Raises:
        ConfigError: none named, or both.
        IncidentStoreError: the store cannot be opened.
    """
    from burstloc.incidents.engine import beside_state
    from burstloc.incidents.store import IncidentStore

    if db is not None and state is not None:
        raise ConfigError("give the incident store by --db or by --state, not both")
    target = db if db is not None else None if state is None else beside_state(state)
    target = target or os.environ.get(DB_VARIABLE)
    if not target:
        raise ConfigError(
            f"which incident store? --db PATH|URL, --state FILE (the monitor's state file) or "
            f"the environment variable {DB_VARIABLE}"
        )
    if state is not None and not os.path.exists(target):
        raise ConfigError(f"no incident store beside the state file {state!r} (no {target!r})")
    return IncidentStore.open(target)


def age(seconds: float) -> str:
    """A duration as an operator reads it: ``45 s``, ``12 min``, ``3 h 05 min``, ``2 d 4 h``."""
    s = max(int(seconds), 0)
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min"
    if s < 86_400:
        return f"{s // 3600} h {s % 3600 // 60:02d} min"
    return f"{s // 86_400} d {s % 86_400 // 3600} h"


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc incidents``."""
    from burstloc.incidents.lifecycle import Outcome, parse_point

    store = open_store(args.db, args.state)
    try:
        if args.action == "list":
            _list(store, args.open, args.limit)
        elif args.action == "show":
            _show(store.get(args.id))
        elif args.action == "export":
            _export(store, args.format, args.out)
        elif args.action == "png":
            _png(store, args)
        elif args.action == "meters":
            _meters(store, args.format, args.out)
        elif args.action == "known-events":
            return _known_events(store, args)
        elif args.action in SHELVING:
            from burstloc.cli.shelving import run as shelving

            shelving(store, args)
        else:
            outcome = None
            if args.action == "close":
                if args.false_alarm:
                    outcome = Outcome.false_alarm()
                else:
                    outcome = Outcome.found(*parse_point(args.found))
            doc = store.act(
                args.id, _ACTIONS[args.action], by=args.by, via="cli", note=args.note,
                outcome=outcome,
            )  # fmt: skip
            print(f"incident {doc['id']}: {doc['state']} ({doc['summary']})")
    finally:
        store.close()
    return 0


def _list(store: Any, open_only: bool, limit: int | None) -> None:
    if limit is not None and limit < 1:
        raise ConfigError(f"--limit must be >= 1, got {limit}")
    rows = store.incidents(open_only=open_only, limit=limit)
    now = time.time()
    if not rows:
        print(f"no incidents in {store.where}", file=sys.stderr)
    else:
        print(f"{'ID':>6}  {'STATE':<12}  {'KIND':<6}  {'AGE':>12}  {'DETECTED':<20}  WHAT")
    for r in rows:
        until = r["shelved_until"]
        shelved = "" if until is None else f"[shelved until {stamp(until)}] "
        print(
            f"{r['id']:>6}  {r['state']:<12}  {r['kind']:<6}  {age(now - r['detected_at']):>12}  "
            f"{stamp(r['detected_at']):<20}  {shelved}{r['summary']}"
        )
    for meter, doc in store.shelves.meters().items():
        print(f"meter {meter} shelved until {stamp(doc['until'])} by {doc['by']}: {doc['reason']}")


def _show(doc: dict[str, Any]) -> None:
    from burstloc.incidents.shelving import SHELVED, action_label

    print(f"incident {doc['id']}: {doc['kind']}, {doc['state']}")
    print(f"  {doc['summary']}")
    print(f"  detected {stamp(doc['detected_at'])} (reading time {doc['reading_time']} s)")
    if doc["outcome"] == "found":
        print(f"  found at {doc['found_x']:g},{doc['found_y']:g}")
    elif doc["outcome"]:
        print(f"  outcome: {doc['outcome']}")
    if doc["shelved_until"] is not None:
        print(
            f"  shelved until {stamp(doc['shelved_until'])} by {doc['shelved_by']}: "
            f"{doc['shelved_reason']}"
        )
    print("history:")
    for h in doc["history"]:
        note = f": {h['note']}" if h["note"] else ""
        until = (h["detail"] or {}).get("until") if h["action"] == SHELVED else None
        note += f" (until {stamp(until)})" if until is not None else ""
        what = action_label(h["action"], h["via"])
        print(f"  {stamp(h['at'])}  {what:<12}  by {h['by']} ({h['via']}){note}")


def _export(store: Any, form: str, out: str | None) -> None:
    from burstloc._atomic import check_output
    from burstloc.incidents.export import export

    if out is not None:
        check_output(out)
    _write(export(store, form), out)


def _write(text: str, out: str | None) -> None:
    """``text`` to stdout, or atomically to ``out`` (said on stderr)."""
    from burstloc._atomic import write_text

    if out is None:
        sys.stdout.write(text)
    else:
        write_text(out, text)
        print(f"wrote {out}", file=sys.stderr)


def _meters(store: Any, form: str, out: str | None) -> None:
    import csv
    import io
    import json

    from burstloc._atomic import check_output
    from burstloc.incidents.outcomes import meter_outcomes

    if out is not None:
        check_output(out)
    rows = meter_outcomes(store.incidents())
    if form == "json":
        _write(json.dumps([m.to_json() for m in rows], indent=1) + "\n", out)
        return
    if form == "csv":
        text = io.StringIO()
        writer = csv.writer(text, lineterminator="\n")
        writer.writerow(("meter", "alarmed", "false_alarms", "found", "incidents",
                         "false_alarm_incidents", "found_incidents"))  # fmt: skip
        for m in rows:
            lists = [" ".join(map(str, x)) for x in (m.incidents, m.false_alarms, m.found)]
            writer.writerow((m.meter, len(m.incidents), len(m.false_alarms), len(m.found), *lists))
        _write(text.getvalue(), out)
        return
    if not rows:
        print(f"no meter has alarmed in an incident of {store.where}", file=sys.stderr)
        return
    lines = [f"{'METER':<16}  {'ALARMED':>7}  {'FALSE ALARMS':>12}  {'FOUND':>5}  INCIDENTS"]
    for m in rows:
        ids = ", ".join(f"{i}{'*' if i in m.false_alarms else ''}" for i in m.incidents)
        lines.append(
            f"{m.meter:<16}  {len(m.incidents):>7}  {len(m.false_alarms):>12}  "
            f"{len(m.found):>5}  {ids}"
        )
    lines.append("(* closed as a false alarm)")
    _write("\n".join(lines) + "\n", out)


def _known_events(store: Any, args: argparse.Namespace) -> int:
    """Write the known-events file; 1 when no found incident could become an event."""
    import math

    from burstloc._atomic import check_output, write_json
    from burstloc.incidents.outcomes import SNAP_WITHIN, known_events
    from burstloc.layout import read_layout

    within = SNAP_WITHIN if args.within is None else args.within
    if not (math.isfinite(within) and within > 0):
        raise ConfigError(f"--within must be a finite distance > 0, got {args.within}")
    check_output(args.out)
    layout = read_layout(args.network)
    entries, refusals = known_events(store.incidents(), layout, args.out, within=within)
    for why in refusals:
        print(f"burstloc incidents: not a known event: {why}", file=sys.stderr)
    if not entries:
        print(
            f"burstloc incidents: no found incident can become a known event "
            f"({len(refusals)} found in {store.where}); {args.out} not written",
            file=sys.stderr,
        )
        return 1
    write_json(args.out, {"events": entries})
    print(
        f"wrote {args.out}: {len(entries)} known event(s), {len(refusals)} found incident(s) "
        "left out (said above)",
        file=sys.stderr,
    )
    return 0


def _png(store: Any, args: argparse.Namespace) -> None:
    from burstloc._atomic import check_output
    from burstloc.web.picture import incident_png, parse_size

    size = parse_size(args.size)
    check_output(args.out)
    incident_png(store, args.id, args.network, args.out, size=size)
    print(f"wrote {args.out}: incident {args.id}, {size[0]}x{size[1]}", file=sys.stderr)
