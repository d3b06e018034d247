"""``burstloc monitor``: the live loop over a feed of readings (a file, stdin or an MQTT topic)."""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
import select
import signal
import sys
from collections.abc import Iterator
from typing import Any

from burstloc.cli import _incidents, _web
from burstloc.constants import DETECTORS, METER_MODELS, RANKING_LOCALIZERS
from burstloc.exceptions import ConfigError, InputError

__all__ = ["add_parser", "run"]


class _StopError(Exception):
    """SIGTERM arrived while waiting for input."""


def _plausible(text: str) -> tuple[str | None, tuple[float, float]]:
    meter, _, bounds = text.rpartition("=")
    low, sep, high = bounds.partition(":")
    try:
        if not sep:
            raise ValueError
        return (meter or None), (float(low), float(high))
    except ValueError:
        raise argparse.ArgumentTypeError(f"want [METER=]LOW:HIGH, got {text!r}") from None


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register ``burstloc monitor``."""
    parser = subparsers.add_parser(
        "monitor",
        help="the live loop: readings in (CSV or MQTT), decision and health records out",
        description=(
            "Read pressure readings 'timestamp,meter,value' (a file, - for stdin, or an MQTT "
            "topic with --mqtt), assemble complete time steps, run the calibrated detector bank "
            "of --config and a ranking localizer built from the localization model stored in it "
            "(no hydraulic model runs), and write JSON lines: one per located burst "
            '("type": "decision") and a health record every --health-every seconds '
            '("type": "health"). Bad readings are reported on stderr and skipped; silent meters '
            "are excluded until they report again. NETWORK.inp is only checked against the "
            "configuration's SHA-256. A decision's \"pipes\" are the three likeliest, best "
            'first; their "score" (fused localizer) is a log-likelihood relative to the best '
            "pipe: 0 for it, -1.2 for a pipe e^-1.2 = 0.3 times as likely. Timestamps: seconds "
            "or ISO 8601 with a UTC offset (read as epoch seconds). Exit status 2 when a file or "
            "stdin held no usable reading."
        ),
    )
    parser.add_argument("network", metavar="NETWORK.inp", help="EPANET INP file")
    parser.add_argument(
        "--config", required=True, metavar="PATH", help="`burstloc calibrate` output"
    )
    parser.add_argument(
        "--capture-interval",
        type=float,
        required=True,
        metavar="S",
        help="s between readings",
    )
    parser.add_argument("--readings", default="-", metavar="FILE", help="CSV file (default: stdin)")
    parser.add_argument("--detector", choices=DETECTORS, default="cusum")
    parser.add_argument("--localizer", choices=RANKING_LOCALIZERS, default="fused")
    parser.add_argument("--meter-model", choices=METER_MODELS, default="instantaneous")
    parser.add_argument(
        "--timeout", type=int, default=3, metavar="N", help="steps to wait for a late reading"
    )
    parser.add_argument(
        "--missing", choices=("skip", "hold"), default="hold", help="policy for incomplete steps"
    )
    parser.add_argument(
        "--classify",
        metavar="FILE",
        help="classifier from `burstloc evaluate --events --classifier-out`: every alarm is "
        "classified burst, other event or unsure; only bursts are reported as decisions",
    )
    parser.add_argument(
        "--operations",
        metavar="CSV",
        help="--classify: declared operations (header asset,time,action) that explain alarms",
    )
    mqtt = parser.add_argument_group("MQTT")
    mqtt.add_argument("--mqtt", metavar="HOST:PORT", help="read readings from this broker")
    mqtt.add_argument("--topic", default="burstloc/readings/#", help="readings topic (subscribe)")
    mqtt.add_argument("--decisions-topic", default="burstloc/decisions", help="publish decisions")
    mqtt.add_argument("--health-topic", default="burstloc/health", help="publish health records")
    mqtt.add_argument("--client-id", help="MQTT client id (default: derived from the setup)")
    mqtt.add_argument(
        "--queue-size", type=int, default=100_000, metavar="N", help="bounded queue, messages"
    )
    live = parser.add_argument_group("operation")
    live.add_argument("--state", metavar="FILE", help="save the state here; resume from it")
    live.add_argument("--save-every", type=float, default=5.0, metavar="S", help="state saves, s")
    live.add_argument(
        "--health-every", type=float, default=60.0, metavar="S", help="health records (0: off)"
    )
    live.add_argument(
        "--silent-after", type=float, default=30.0, metavar="S", help="exclude a silent meter"
    )
    live.add_argument("--clock-tolerance", type=float, metavar="S", help="clock offset allowed")
    live.add_argument(
        "--plausible",
        type=_plausible,
        action="append",
        default=[],
        metavar="[METER=]LOW:HIGH",
        help="believable readings, m (default: -10 m to twice the highest steady head)",
    )
    from burstloc.cli import _service

    _service.add_arguments(parser)
    _web.add_arguments(parser)
    _incidents.add_arguments(parser)
    parser.set_defaults(handler=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Handle ``burstloc monitor``."""
    from burstloc.live.health import Health
    from burstloc.live.loop import LiveLoop
    from burstloc.live.monitor import BurstMonitor
    from burstloc.live.observe import fan_out
    from burstloc.live.plausible import PlausibleRange
    from burstloc.live.reporter import Reporter
    from burstloc.live.state import StateFile, identity
    from burstloc.localize.config import Calibration

    if args.queue_size < 1:
        raise ConfigError(f"--queue-size must be >= 1, got {args.queue_size}")
    for option, value in [("--save-every", args.save_every), ("--health-every", args.health_every)]:
        if not 0 <= value < float("inf"):
            raise ConfigError(f"{option} must be a finite number >= 0, got {value}")
    config = Calibration.load(args.config)
    classify, operations = None, []
    if args.classify:
        from burstloc.localize.classify import ClassifierConfig, read_operations

        classify = ClassifierConfig.load(args.classify)
        operations = read_operations(args.operations) if args.operations else []
    elif args.operations:
        raise ConfigError("--operations needs --classify")
    monitor = BurstMonitor(
        args.network,
        config,
        capture_interval=args.capture_interval,
        detector=args.detector,
        localizer=args.localizer,
        meter_model=args.meter_model,
        classify=classify,
        operations=operations,
    )
    plausible = PlausibleRange.default(monitor.meters, monitor.steady.tolist())
    health = Health(
        monitor.meters,
        plausible.with_overrides(dict(args.plausible)),
        capture_interval=args.capture_interval,
        silent_after=args.silent_after,
        clock_tolerance=args.clock_tolerance,
    )
    flags = {"waiting": False, "stop": False}
    with contextlib.ExitStack() as stack:  # whatever started is stopped, in reverse order
        recorder = _incidents.start(args, lambda text: write(text), monitor.meters)
        alerts: dict[str, Any] = {"sender": None}
        stack.callback(lambda: _incidents.stop(recorder, alerts["sender"]))
        web = _web.start(args, monitor, None if recorder is None else recorder.store)
        if web is not None:
            stack.callback(web.stop)

        def write(text: str) -> None:
            print(text, file=sys.stderr, flush=True)
            if web is not None:
                web.hub.message(text.removeprefix("burstloc monitor: "))

        report = Reporter(write)
        ident = identity(
            config,
            capture_interval=args.capture_interval,
            detector=args.detector,
            localizer=args.localizer,
            meter_model=args.meter_model,
        )
        state = None if args.state is None else StateFile(args.state, ident)

        def on_term(signum: int, frame: Any) -> None:
            flags["stop"] = True
            if flags["waiting"]:
                raise _StopError

        # before the broker link connects (and says so): a SIGTERM from then on stops cleanly
        stack.callback(signal.signal, signal.SIGTERM, signal.signal(signal.SIGTERM, on_term))
        link = _link(args, ident, report)
        if link is not None:
            stack.callback(link.close)

        def emit(record: dict[str, Any]) -> None:
            print(json.dumps(record), flush=True)
            if link is not None:
                topic = args.decisions_topic if record["type"] == "decision" else args.health_topic
                link.publish(topic, record)

        loop = LiveLoop(
            monitor,
            health,
            emit,
            report,
            timeout=args.timeout,
            missing=args.missing,
            health_every=args.health_every,
            state=state,
            save_every=args.save_every,
            observer=fan_out(None if web is None else web.hub, recorder),
        )
        sender = alerts["sender"] = _incidents.start_alerts(args, recorder, loop, web, write)
        try:
            _serve(args, loop, state, link, web, recorder, sender, flags, report)
        except _StopError:
            loop.finish()
    if flags["stop"]:
        saved_to = f"; state saved to {args.state}" if args.state else ""
        print(f"burstloc monitor: stopped by SIGTERM{saved_to}", file=sys.stderr)
    elif link is None and loop.readings == 0:
        source = "stdin" if args.readings == "-" else repr(args.readings)
        raise InputError(f"no usable readings in {source}: nothing was monitored")
    return 0


def _serve(
    args: argparse.Namespace,
    loop: Any,
    state: Any,
    link: Any,
    web: Any,
    recorder: Any,
    sender: Any,
    flags: dict[str, bool],
    report: Any,
) -> None:
    """Resume from the state file, then run ``loop`` over the readings until they end (or, from
    a broker, until SIGTERM), serving the page after a finished file while it is open."""
    from burstloc.cli import _service

    metrics = _service.attach(args, web, loop, link)
    if metrics is not None and recorder is not None:  # the incident store's counts
        store = recorder.store
        metrics.incidents_open = store.open_count
        metrics.meter_counts = store.meter_counts
        metrics.webhooks = sender
    saved = None if state is None else state.load()
    if saved is not None:
        try:
            loop.restore(saved)
        except ConfigError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError, IndexError) as exc:
            raise ConfigError(f"state file {args.state!r} is malformed: {exc!r}") from exc
        report("state", f"resumed from state file {args.state}")
    if link is not None:
        items: Iterator[Any] = _from_broker(link, flags)
    else:
        idle = min(max(args.save_every, 0.05), 1.0)
        # as rows of what each read gives, unless paced reading by reading
        columns = None if args.replay_speed is not None else loop.monitor.meters
        items = _from_file(args.readings, flags, idle, loop.timestamps, columns)
        if args.replay_speed is not None:
            from burstloc.live.replay import paced

            items = paced(items, args.replay_speed, lambda: flags["stop"])
    items = _service.reloading(items, args, loop=loop, web=web, metrics=metrics, report=report)
    loop.run(items)
    if web is not None and link is None and args.readings != "-":
        _web.linger(web, lambda: flags["stop"])


def _link(args: argparse.Namespace, ident: Any, report: Any) -> Any:
    """The MQTT link of ``--mqtt`` (connecting in the background), or ``None``."""
    if args.mqtt is None:
        return None
    from burstloc.live.mqtt import MqttLink, parse_address

    host, port = parse_address(args.mqtt)
    digest = hashlib.sha256(json.dumps([ident, args.topic]).encode()).hexdigest()[:12]
    return MqttLink(
        host,
        port,
        args.topic,
        client_id=args.client_id or f"burstloc-monitor-{digest}",
        report=report,
        queue_size=args.queue_size,
    )


def _from_broker(link: Any, flags: dict[str, bool]) -> Iterator[Any]:
    for message in link.messages():
        if flags["stop"]:
            return
        if message is None:
            yield None
            continue
        number, payload = message
        yield f"message {number}", payload  # the loop parses it as one row


def _from_file(
    path: str, flags: dict[str, bool], idle: float, form: Any, meters: Any = None
) -> Iterator[Any]:
    """The items of the CSV lines of ``path`` (``-``: stdin) and ``None`` after ``idle`` seconds
    without input (the loop then saves its state and checks silence while it waits); ``form``:
    the feed's timestamp form (:class:`~burstloc.live.parse.TimestampForm`). With ``meters``
    (the configuration's), the lines of each read as one ``(where, row)`` over them
    (:func:`~burstloc.live.lines.rows_of_lines`: each report names its line), else ``(where,
    item)`` per line."""
    from burstloc.live.lines import rows_of_lines
    from burstloc.live.parse import BadReading, parse_line

    try:
        source = sys.stdin.buffer if path == "-" else open(path, "rb")  # noqa: SIM115
    except OSError as exc:
        raise InputError(f"cannot read readings {path!r}: {exc.strerror}") from exc
    columns = None if meters is None else {m: j for j, m in enumerate(meters)}
    number = 0
    try:
        for lines in _raw_lines(source, flags, idle):
            if lines is None:
                yield None
                continue
            if columns is not None:
                row = rows_of_lines(lines, number + 1, columns, form, _LONGEST)
                if row.size:
                    yield f"lines {number + 1}-{number + len(lines)}", row
                number += len(lines)
                continue
            for line in lines:
                number += 1
                where = f"line {number}"
                if len(line) > _LONGEST:
                    yield where, BadReading(where, f"line longer than {_LONGEST} bytes")
                    continue
                item = parse_line(line, where, form)
                if item is not None:
                    yield where, item
    finally:
        if source is not sys.stdin.buffer:
            source.close()


_LONGEST = 1 << 16  # bytes in one CSV line; a longer one is bad input, not a reason to stop
_CHUNK = 1 << 16


def _raw_lines(source: Any, flags: dict[str, bool], idle: float) -> Iterator[list[bytes] | None]:
    """The lines of ``source`` as bytes, those of each read together, read unbuffered from its
    file descriptor so that a pipe with nothing to read gives ``None`` every ``idle`` seconds
    instead of blocking; an overlong line is cut short (the caller reports it) and the rest of
    it skipped."""
    fd = source.fileno()
    pending = b""
    skipping = False
    while not flags["stop"]:
        flags["waiting"] = True
        try:
            data = os.read(fd, _CHUNK) if _readable(fd, idle) else None
        finally:
            flags["waiting"] = False
        if data is None:
            yield None
            continue
        if not data:
            break
        pending += data
        *complete, pending = pending.split(b"\n")
        if skipping and complete:
            skipping = False
            complete = complete[1:]
        if len(pending) > _LONGEST and not skipping:
            complete.append(pending[: _LONGEST + 1])
            pending, skipping = b"", True
        elif skipping:
            pending = b""
        if complete:
            yield complete
    if pending and not skipping and not flags["stop"]:
        yield [pending]


def _readable(fd: int, timeout: float) -> bool:
    """Whether ``fd`` has input (or end of file) within ``timeout`` seconds; a descriptor
    ``select`` cannot watch (a Windows pipe) counts as readable, and the read then blocks."""
    try:
        return bool(select.select([fd], [], [], timeout)[0])
    except (OSError, ValueError):
        return True
