"""``burstloc incidents shelve | unshelve | shelve-meter | unshelve-meter``: take an incident
(or a meter's faults) out of the way for a while, with a reason; it comes back by itself
(:mod:`burstloc.incidents.shelving`). Part of ``burstloc incidents``
(:mod:`burstloc.cli.incidents`)."""

from __future__ import annotations

import argparse
from typing import Any

__all__ = ["SHELVING", "add_parsers", "run"]

#: The actions of ``burstloc incidents`` this module handles.
SHELVING = ("shelve", "unshelve", "shelve-meter", "unshelve-meter")


def add_parsers(actions: Any, where: argparse.ArgumentParser) -> None:
    """Register the shelving actions under ``burstloc incidents`` (``where``: the store's
    options)."""
    most = "at most 24h"
    for name, what, text in [
        ("shelve", "id", "take an open incident out of the way for a while (not escalated)"),
        ("unshelve", "id", "bring a shelved incident back before its time"),
        ("shelve-meter", "meter", "shelve a meter's faults (maintenance); still localizes"),
        ("unshelve-meter", "meter", "end a meter's shelving before its time"),
    ]:
        act = actions.add_parser(name, parents=[where], help=text, description=text + ".")
        if what == "id":
            act.add_argument("id", type=int, metavar="ID")
        else:
            act.add_argument("meter", metavar="METER")
        act.add_argument("--by", required=True, metavar="NAME", help="who acts (recorded)")
        if name.startswith("shelve"):
            act.add_argument(
                "--for", dest="duration", required=True, metavar="TIME",
                help=f"how long: 30m, 2h, 1h30m ({most}); it comes back by itself then",
            )  # fmt: skip
            act.add_argument("--reason", required=True, metavar="TEXT", help="why (recorded)")
        elif name == "unshelve":
            act.add_argument("--note", metavar="TEXT", help="a note")


def run(store: Any, args: argparse.Namespace) -> None:
    """Handle one of :data:`SHELVING`."""
    from burstloc.cli._incidents import stamp
    from burstloc.incidents.shelving import parse_duration

    shelves = store.shelves
    if args.action == "shelve":
        doc = shelves.shelve(
            args.id, parse_duration(args.duration), by=args.by, via="cli", reason=args.reason
        )
        until = stamp(doc["shelved_until"])
        print(f"incident {doc['id']}: shelved until {until} ({doc['summary']})")
    elif args.action == "unshelve":
        doc = shelves.unshelve(args.id, by=args.by, via="cli", note=args.note)
        print(f"incident {doc['id']}: {doc['state']}, unshelved ({doc['summary']})")
    elif args.action == "shelve-meter":
        got = shelves.shelve_meter(
            args.meter, parse_duration(args.duration), by=args.by, via="cli", reason=args.reason
        )
        print(
            f"meter {args.meter.strip()}: shelved until {stamp(got['until'])}: its faults arrive "
            "shelved meanwhile (it still takes part in localization)"
        )
    else:
        shelves.unshelve_meter(args.meter, by=args.by, via="cli")
        print(f"meter {args.meter.strip()}: unshelved")
