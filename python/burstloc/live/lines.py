"""A feed file's lines as rows: what ``burstloc monitor --readings FILE`` (or ``-``, standard
input) reads at once is parsed as one :class:`~burstloc.live.parse.Row` and fed to the live loop
as a row (:meth:`burstloc.live.loop.LiveLoop.feed_row`): the same items in the same order, the
same bad ones with the same reasons, the same decisions, health and reports as the lines fed one
by one, each report naming its line, without an object per reading. The common line
(``seconds,meter,value``, a configured meter, finite numbers, in a feed of seconds) is read
inline; every other line goes through :func:`~burstloc.live.parse.parse_line` as before. At
33 meters and 250 Hz the lines cost the loop about a quarter of what they cost one by one
(``benches/bench_rate.py``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from burstloc.live.parse import SECONDS, BadReading, Row, TimestampForm, parse_line, unknown_meter

__all__ = ["rows_of_lines"]


def rows_of_lines(
    lines: Sequence[bytes],
    first: int,
    columns: Mapping[str, int],
    form: TimestampForm,
    longest: int,
) -> Row:
    """The items of ``lines`` (numbered from ``first``) as one row over the meters ``columns``
    (name → column): blank lines, comments and headers are not items; a line longer than
    ``longest`` bytes, one :func:`~burstloc.live.parse.parse_line` refuses and one from a meter
    not in ``columns`` are bad items named by their line. ``form``: the feed's timestamp form
    (fixed by its first reading, here or before). Never raises."""
    positions: list[int] = []
    times: list[float] = []
    cols: list[int] = []
    values: list[float] = []
    bad: list[tuple[int, BadReading]] = []
    numbers: list[int] = []
    named = {name.encode(): j for name, j in columns.items()}
    seconds = form.form == SECONDS
    for k, line in enumerate(lines):
        number = first + k
        if len(line) > longest:
            long = BadReading(f"line {number}", f"line longer than {longest} bytes")
            bad.append((len(numbers), long))
            numbers.append(number)
            continue
        if seconds:  # the common line, inline: the same reading parse_line would give
            fields = line.split(b",")
            j = named.get(fields[1]) if len(fields) == 3 else None
            if j is not None:
                try:
                    t, value = float(fields[0]), float(fields[2])
                except ValueError:
                    pass
                else:
                    if t - t == value - value == 0.0:  # finite (NaN and infinities give NaN)
                        positions.append(len(numbers))
                        times.append(t)
                        cols.append(j)
                        values.append(value)
                        numbers.append(number)
                        continue
        where = f"line {number}"
        item = parse_line(line, where, form)
        if item is None:
            continue
        if isinstance(item, BadReading):
            bad.append((len(numbers), item))
        elif (j := columns.get(item.meter)) is None:
            bad.append((len(numbers), unknown_meter(where, item.meter)))
        else:
            positions.append(len(numbers))
            times.append(item.timestamp)
            cols.append(j)
            values.append(item.value)
        numbers.append(number)
        seconds = form.form == SECONDS  # the feed's first reading fixes its form
    return Row(positions, times, cols, values, bad, len(numbers), numbers)
