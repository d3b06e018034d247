"""burstloc.layout: a pipe's drawing from its INP start node, and the pipe nearest a point."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from burstloc.layout import drawn_lengths, read_layout

BENT = """\
[JUNCTIONS]
 A  0  0
 B  0  0
 C  0  0
[RESERVOIRS]
 R  50
[PIPES]
 P1  A  B  100  100  100  0  Open
 P2  C  B  100  100  100  0  Open
 P3  R  A  100  100  100  0  Open
[COORDINATES]
 R  -1000  0
 A  0    0
 B  100  0
 C  100  100
[VERTICES]
 P1  50  50
[END]
"""


@pytest.fixture
def bent(tmp_path: Path) -> Path:
    """P1 from A (0, 0) up to a vertex (50, 50) and down to B (100, 0); P2 from C down to B;
    P3 from R far to the left to A."""
    path = tmp_path / "bent.inp"
    path.write_text(BENT, encoding="utf-8")
    return path


def test_a_pipes_line_runs_from_its_inp_start_node_through_its_vertices(bent: Path) -> None:
    layout = read_layout(bent)
    assert layout.line("P1") == [(0.0, 0.0), (50.0, 50.0), (100.0, 0.0)]
    assert layout.line("P2") == [(100.0, 100.0), (100.0, 0.0)]
    assert drawn_lengths(layout.line("P1")) == pytest.approx(
        [0, 50 * math.sqrt(2), 100 * math.sqrt(2)]
    )


@pytest.mark.parametrize(
    ("x", "y", "pipe", "fraction", "gap"),
    [
        (25.0, 25.0, "P1", 0.25, 0.0),  # on the first leg of the bent pipe
        (80.0, 30.0, "P1", 0.75, math.sqrt(2) * 5),  # beside the middle of the second leg
        (110.0, 40.0, "P2", 0.6, 10.0),  # beside P2, 60 % from C
        (
            30.0,
            -40.0,
            "P1",
            0.0,
            50.0,
        ),  # nearest A: P1's start and P3's end tie, P1 is listed first
        (-500.0, 1.0, "P3", 0.5, 1.0),  # beside P3's middle
    ],
)
def test_the_nearest_pipe_and_where_along_it(
    bent: Path, x: float, y: float, pipe: str, fraction: float, gap: float
) -> None:
    found = read_layout(bent).nearest_pipe(x, y)
    assert found is not None
    assert found[0] == pipe
    assert found[1] == pytest.approx(fraction, abs=1e-9)
    assert found[2] == pytest.approx(gap, abs=1e-9)
