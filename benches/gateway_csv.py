"""Seeded pressure readings as the Rust gateway example reads them, for timing it.

Usage::

    .venv/bin/python benches/gateway_csv.py --channels 1024 --rows 4000 > readings.csv
    cargo build --release --example gateway -p cpd-core
    target/release/examples/gateway --threshold 0.3 --drift 0.01 < readings.csv > /dev/null

The gateway prints its readings per second on stderr. The CSV has a header line
(``time,m0,...``) and one line per time step (``--interval`` s apart): every meter's head is a
level drawn in 150-220 m plus Gaussian sensor noise of 0.05 m, and in every block of 2,000 rows
about 2 % of the meters drop by 0.5-2 m at a random row and stay there (a burst). Heads are
written with ``--digits`` decimals (4: a millimetre, as loggers report them); ``--digits -1``
writes Python's shortest round-trip form (up to 17 significant digits), the slowest to parse.
"""

from __future__ import annotations

import argparse
import sys
from typing import TextIO

import numpy as np

BLOCK = 2_000  # rows generated at a time
NOISE = 0.05  # m


def write_csv(
    out: TextIO, channels: int, rows: int, digits: int, interval: float, seed: int
) -> None:
    """Write the header and ``rows`` lines of ``channels`` heads to ``out``."""
    rng = np.random.default_rng(seed)
    level = rng.uniform(150.0, 220.0, channels)
    out.write("time," + ",".join(f"m{c}" for c in range(channels)) + "\n")
    for first in range(0, rows, BLOCK):
        n = min(BLOCK, rows - first)
        heads = level + rng.normal(0.0, NOISE, (n, channels))
        burst = rng.random(channels) < 0.02
        if burst.any():
            at = rng.integers(0, n)
            drop = rng.uniform(0.5, 2.0, int(burst.sum()))
            heads[at:, burst] -= drop
            level[burst] -= drop
        times = (first + np.arange(n)) * interval
        if digits >= 0:
            fmt = "%.3f" + f",%.{digits}f" * channels
            np.savetxt(out, np.column_stack([times, heads]), fmt=fmt)
        else:
            for t, row in zip(times.tolist(), heads.tolist(), strict=True):
                out.write(repr(t) + "," + ",".join(map(repr, row)) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--channels", type=int, default=1_024)
    parser.add_argument("--rows", type=int, default=4_000)
    parser.add_argument("--digits", type=int, default=4, help="decimals; -1: shortest repr")
    parser.add_argument("--interval", type=float, default=0.1, help="seconds between rows")
    parser.add_argument("--seed", type=int, default=2026)
    args = parser.parse_args()
    if args.channels < 1 or args.rows < 1:
        parser.error("--channels and --rows must be at least 1")
    write_csv(sys.stdout, args.channels, args.rows, args.digits, args.interval, args.seed)


if __name__ == "__main__":
    main()
