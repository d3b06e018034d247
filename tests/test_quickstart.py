"""The README's Python quickstart (docs/quickstart.py, included verbatim) runs and is right."""

from __future__ import annotations

import contextlib
import io
import runpy
from pathlib import Path

from reference import cusum_online

ROOT = Path(__file__).resolve().parents[1]
QUICKSTART = ROOT / "docs" / "quickstart.py"


def test_quickstart_prints_the_burst_alarm() -> None:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        scope = runpy.run_path(str(QUICKSTART), run_name="__main__")
    lines = out.getvalue().splitlines()
    expected = cusum_online(scope["head"].tolist(), 0.5, 0.05)
    # The burst, and only the burst, is reported: at sample 3000, starting at 2999, a drop.
    assert [(a.index, a.start, a.direction) for a in expected] == [(3000, 2999, "drop")]
    alarm = expected[0]
    assert lines == [
        f"Alarm(index={alarm.index}, start={alarm.start}, direction='{alarm.direction}', "
        f"amplitude={alarm.amplitude!r})"
    ]


def test_quickstart_is_ten_lines_of_code() -> None:
    code = [line for line in QUICKSTART.read_text().splitlines() if line.strip()]
    assert len(code) <= 10


def test_readme_shows_the_quickstart_verbatim() -> None:
    assert QUICKSTART.read_text().strip() in (ROOT / "README.md").read_text()
