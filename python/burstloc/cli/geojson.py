"""``burstloc geojson``: a monitor record's search region, named point and meters as GeoJSON."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from burstloc._atomic import check_output
from burstloc.exceptions import ConfigError, InputError

__all__ = ["add_parser", "run"]


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc geojson``."""
    parser = subparsers.add_parser(
        "geojson",
        help="a located burst for GIS: the record's search region, named point and meters as "
        "GeoJSON",
        description="Write a record of `burstloc monitor` (a decision, an early transient "
        "record or an event) as a GeoJSON FeatureCollection: each stretch of its search region "
        "as a LineString (with its probability), the named point as a Point and its interval "
        "on the pipe as a LineString, each meter as a Point (alarmed, excluded). A distance "
        "along a pipe is placed on the pipe's drawing in proportion to its length in the INP "
        "file. Coordinates are the INP file's, or with --crs, transformed from that system to "
        "WGS 84 longitude, latitude (needs pyproj: pip install 'burstloc[gis]').",
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="the network the record is of")
    parser.add_argument(
        "--record",
        default="-",
        metavar="FILE",
        help="the monitor's output (JSON lines; or one JSON record), - for stdin (default)",
    )
    parser.add_argument(
        "--index",
        type=int,
        default=-1,
        metavar="N",
        help="which located record of FILE: 1 the first, -1 the last (default), -2 the one "
        "before it",
    )
    parser.add_argument(
        "--crs",
        metavar="EPSG:NNNN",
        help="the network's coordinate reference system: write WGS 84 longitude, latitude",
    )
    parser.add_argument("--out", metavar="FILE", help="write here (default: stdout)")
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc geojson``."""
    from burstloc.gis import located_records, record_geojson
    from burstloc.layout import read_layout

    if args.out is not None:
        check_output(args.out)
    layout = read_layout(args.network)
    source = "stdin" if args.record == "-" else args.record
    try:
        if args.record == "-":
            text = sys.stdin.read()
        else:
            with open(args.record, encoding="utf-8") as handle:
                text = handle.read()
    except OSError as exc:
        raise InputError(f"cannot read records {source!r}: {exc.strerror}") from exc
    except UnicodeDecodeError as exc:
        raise InputError(f"records {source!r} are not UTF-8 text: {exc}") from None
    records = located_records(text, source)
    if not records:
        raise InputError(f"{source}: no record with a region or a named point")
    if args.index == 0 or abs(args.index) > len(records):
        raise ConfigError(
            f"--index {args.index}: {source} holds {len(records)} located record(s); give 1.."
            f"{len(records)} or -1..-{len(records)}"
        )
    where, record = records[args.index - 1 if args.index > 0 else args.index]
    collection = record_geojson(layout, record, crs=args.crs, source=where)
    text = json.dumps(collection)
    if args.out is None:
        print(text)
    else:
        from burstloc._atomic import write_text

        write_text(args.out, text + "\n")
        count = len(collection["features"])
        print(f"wrote {args.out}: {count} features of {where}", file=sys.stderr)
    return 0
