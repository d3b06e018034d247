"""Every command fails cleanly and loses nothing: one test per failure class, driving
``burstloc`` as a subprocess on the tiny network (a traceback, a silent exit or a lost file
fails the test).

Classes: outputs checked before any work; invalid results never written; configurations
validated on load; networks validated on load; cache entries verified on read; Ctrl-C and a
closed stdout; every error inside the contract.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from conftest import REPO, write_tiny

SHORT = ["--burst-start", "0.2", "--duration", "1.5", "--quiet", "--workers", "1"]
#: Quick evaluate options: one pipe, one capture interval, one phase, in this process.
EVALUATE = ["--pipes", "A", "--capture-interval", "1", "--phases", "1", "--quiet"]
EVALUATE += ["--workers", "1", "--detector", "cusum"]
#: The command line of ``burstloc`` run by this Python.
BURSTLOC = [sys.executable, "-m", "burstloc"]


def burstloc(
    *args: str | Path, cache: Path | None = None, stdin: str | None = None
) -> subprocess.CompletedProcess[str]:
    """Run ``python -m burstloc ARGS`` and return the finished process (text output)."""
    return subprocess.run(
        [*BURSTLOC, *map(str, args)],
        capture_output=True,
        text=True,
        input=stdin,
        env=_env(cache),
        check=False,
    )


def _env(cache: Path | None) -> dict[str, str]:
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    if cache is not None:
        env["BURSTLOC_CACHE_DIR"] = str(cache)
    return env


def refused(proc: subprocess.CompletedProcess[str], *fragments: str) -> str:
    """Assert a clean refusal: exit 2, one ``burstloc: error:`` line holding ``fragments``,
    no traceback; return the message."""
    assert "Traceback" not in proc.stderr, proc.stderr
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    lines = [line for line in proc.stderr.splitlines() if line.startswith("burstloc: error: ")]
    assert len(lines) == 1, proc.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope="module")
def tiny(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_tiny(tmp_path_factory.mktemp("net") / "tiny.inp")


@pytest.fixture(scope="module")
def good_config(tiny: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A configuration written by ``burstloc calibrate`` for the tiny network at 1 s."""
    out = tmp_path_factory.mktemp("cfg") / "good.json"
    proc = burstloc("calibrate", tiny, "--out", out, "--capture-interval", "1")
    assert proc.returncode == 0, proc.stderr
    return out


def _empty(directory: Path) -> bool:
    return not directory.exists() or not any(p.is_file() for p in directory.rglob("*"))


# --- 1. outputs are checked before any work -------------------------------------------------


@pytest.mark.parametrize(
    ("command", "option", "kind"),
    [
        ("evaluate", "--json", "missing-dir"),
        ("evaluate", "--plot", "under-a-file"),
        ("calibrate", "--out", "is-a-directory"),
        ("study", "--out", "under-a-file"),
        ("simulate", "--out", "under-a-file"),
        ("place", "--out", "missing-dir"),
    ],
)
def test_an_unwritable_output_is_refused_before_any_work(
    tiny: Path, tmp_path: Path, command: str, option: str, kind: str
) -> None:
    (tmp_path / "afile").write_text("x")
    (tmp_path / "adir").mkdir()
    target = {
        "missing-dir": tmp_path / "missing" / "out.json",
        "is-a-directory": tmp_path / "adir",
        "under-a-file": tmp_path / "afile" / "out",
    }[kind]
    args: list[str | Path] = [command, tiny]
    if command == "evaluate":
        args += EVALUATE
    elif command == "simulate":
        args += ["--pipe", "A", *SHORT]
    elif command == "study":
        args += ["--factors", "noise_sigma", "--pipes", "A", "--quiet", "--workers", "1"]
    elif command == "calibrate":
        args += ["--capture-interval", "1"]
    elif command == "place":
        args += ["--meters", "2", "--method", "coverage"]
    cache = tmp_path / "cache"
    proc = burstloc(*args, option, target, cache=cache)
    refused(proc, f"cannot write {target}: ")
    assert _empty(cache), "work was done before the output was checked"
    assert proc.stdout == ""


def test_an_unwritable_directory_is_refused(tiny: Path, tmp_path: Path) -> None:
    # /proc is not writable even by root: a real unwritable directory wherever tests run
    proc = burstloc("evaluate", tiny, *EVALUATE, "--json", "/proc/out.json", cache=tmp_path)
    refused(proc, "cannot write /proc/out.json: ")


# --- 2. invalid results are never written ---------------------------------------------------


@pytest.mark.parametrize(
    ("extra", "inp_edit", "fragments"),
    [
        ([], "empty", ("no junctions",)),
        (["--capture-interval", "1e308"], None, ("capture interval", "1e+308")),
        (["--meters", "J2", "J2"], None, ("J2", "more than once")),
        ([], "negative-length", ("pipe 'A'", "length", "-300")),
    ],
)
def test_calibrate_refuses_bad_input_and_keeps_the_good_configuration(
    tiny: Path,
    good_config: Path,
    tmp_path: Path,
    extra: list[str],
    inp_edit: str | None,
    fragments: tuple[str, ...],
) -> None:
    network = tmp_path / "net.inp"
    text = tiny.read_text()
    network.write_text(
        {
            None: text,
            "empty": "",
            "negative-length": text.replace(" A    R1     J1     300", " A    R1     J1     -300"),
        }[inp_edit]
    )
    out = tmp_path / "config.json"
    out.write_bytes(good_config.read_bytes())
    proc = burstloc("calibrate", network, "--out", out, *(extra or ["--capture-interval", "1"]))
    refused(proc, *fragments)
    assert out.read_bytes() == good_config.read_bytes()


# --- 3. configurations are validated on load ------------------------------------------------


def _edited(good: Path, tmp_path: Path, edit) -> Path:  # type: ignore[no-untyped-def]
    doc = json.loads(good.read_text())
    edited = edit(doc)
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(doc if edited is None else edited))
    return path


@pytest.mark.parametrize(
    ("edit", "fragments"),
    [
        (lambda d: [1, 2], ("must be a JSON object", "a list")),
        (
            lambda d: d["intervals"][0].update(localization_interval=10**12),
            ("intervals[0].localization_interval", "1000000000000"),
        ),
        (
            lambda d: d["intervals"][0].update(decision_delay_s=float("nan")),
            ("NaN",),
        ),
        (lambda d: d.update(meters=["J1", "J1", "J2", "J3"]), ("meters", "'J1'", "more than once")),
        (
            lambda d: d["intervals"][0]["cusum"]["threshold"].update(J1="high"),
            ("intervals[0].cusum.threshold.J1", "number"),
        ),
    ],
)
def test_a_bad_configuration_is_refused_naming_file_and_field(
    tiny: Path, good_config: Path, tmp_path: Path, edit, fragments: tuple[str, ...]
) -> None:  # type: ignore[no-untyped-def]
    path = _edited(good_config, tmp_path, edit)
    proc = burstloc("evaluate", tiny, *EVALUATE, "--config", path, cache=tmp_path / "c")
    refused(proc, str(path), *fragments)
    assert _empty(tmp_path / "c")


def test_the_monitor_refuses_a_huge_localization_interval(
    tiny: Path, good_config: Path, tmp_path: Path
) -> None:
    def edit(d):  # type: ignore[no-untyped-def]
        d["intervals"][0]["localization_interval"] = 10**12

    path = _edited(good_config, tmp_path, edit)
    proc = burstloc("monitor", tiny, "--config", path, "--capture-interval", "1", stdin="")
    refused(proc, str(path), "localization_interval")


@pytest.mark.parametrize("content", [b"\xff\xfe{", b'{"format": "burstloc-calibration/2",'])
def test_an_unreadable_configuration_is_refused(tiny: Path, tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "bad.json"
    path.write_bytes(content)
    proc = burstloc("evaluate", tiny, *EVALUATE, "--config", path, cache=tmp_path / "c")
    refused(proc, str(path))


# --- 4. networks are validated on load ------------------------------------------------------


def test_a_non_utf8_network_is_named_with_its_line(tiny: Path, tmp_path: Path) -> None:
    network = tmp_path / "latin.inp"
    network.write_bytes(tiny.read_bytes().replace(b"tiny test network", b"tiny r\xe9seau"))
    proc = burstloc("simulate", network, "--pipe", "A", *SHORT, "--out", tmp_path / "o")
    refused(proc, f"{network}:2:", "UTF-8")


# --- 5. cache entries are verified on read --------------------------------------------------


def test_a_corrupt_cache_entry_is_reported_dropped_and_recomputed(
    tiny: Path, tmp_path: Path
) -> None:
    cache, out = tmp_path / "cache", tmp_path / "out"
    args = ("simulate", tiny, "--pipe", "A", *SHORT, "--out", out, "--cache-dir", cache)
    assert burstloc(*args).returncode == 0
    (first,) = out.iterdir()
    with np.load(first, allow_pickle=False) as data:
        expected = data["heads"]
    (entry,) = cache.rglob("*.npz")
    with np.load(entry, allow_pickle=False) as data:
        arrays = {name: data[name] for name in data.files}
    arrays["heads"] = np.full_like(arrays["heads"], np.nan)  # the checksum no longer fits
    np.savez(entry, **arrays)
    proc = burstloc(*args)
    assert proc.returncode == 0, proc.stderr
    assert "Traceback" not in proc.stderr
    assert f"cache entry {entry}" in proc.stderr and "recomputing" in proc.stderr
    with np.load(first, allow_pickle=False) as data:  # recomputed: the same heads
        np.testing.assert_array_equal(data["heads"], expected)
    with np.load(entry, allow_pickle=False) as data:
        assert np.isfinite(data["heads"]).all()


# --- 6. signals and pipes -------------------------------------------------------------------


#: evaluate in this process with its progress bar on, then ``--json PATH``.
INTERRUPTIBLE = ["--capture-interval", "1", "--json"]

#: Loaded by every Python process of the interrupted run (``PYTHONPATH``), the worker processes
#: included: each burst simulation first says that it started (a line in the file named by
#: ``BURSTLOC_TEST_STARTED``) and then simulates its burst again and again, so the run is
#: always simulating when the signal lands, however fast or loaded the machine is.
_NEVER_ENDING_SIMULATION = """
import os
import signal
import time

import burstloc.sim.transient.tsnet as _tsnet

# Ctrl-C as a terminal delivers it, also where the suite itself runs with SIGINT ignored (a job
# a shell without job control starts in the background inherits that, and Python then raises no
# KeyboardInterrupt): this process and its workers take it as Python does by default.
signal.signal(signal.SIGINT, signal.default_int_handler)

_simulate = _tsnet._simulate_uncached


def _simulate_forever(scenario):
    # One real simulation, then a wait that never ends, said started only then: a Ctrl-C sent
    # during TSNet's own code can be swallowed by its bare `except:` clauses (the sweep then
    # stops after the item, which here never ends), so the signal is sent into the wait.
    _simulate(scenario)
    with open(os.environ["BURSTLOC_TEST_STARTED"], "a") as started:
        started.write(f"{os.getpid()}\\n")
    while True:
        time.sleep(0.01)


_tsnet._simulate_uncached = _simulate_forever
"""


@pytest.mark.parametrize("workers", ["1", "2"])
def test_ctrl_c_prints_one_line_exits_130_and_keeps_the_output(
    tiny: Path, good_config: Path, tmp_path: Path, workers: str
) -> None:
    out = tmp_path / "results.json"
    out.write_text('{"kept": true}\n')
    cache = tmp_path / "cache"
    hooks = tmp_path / "hooks"
    hooks.mkdir()
    (hooks / "sitecustomize.py").write_text(_NEVER_ENDING_SIMULATION)
    started = tmp_path / "started.txt"
    env = _env(cache)
    env["PYTHONPATH"] = os.pathsep.join([str(hooks), env["PYTHONPATH"]])
    env["BURSTLOC_TEST_STARTED"] = str(started)
    # Its own process group, interrupted as a terminal does it: SIGINT to the whole group, the
    # worker processes included.
    pipes = ["A", "B", "C", "D", "E"]
    command = [*BURSTLOC, "evaluate", str(tiny), "--pipes", *pipes, "--workers", workers]
    proc = subprocess.Popen(
        [*command, *INTERRUPTIBLE, str(out)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
    )
    # No deadline: the run cannot end before the signal (its simulations never end); one that
    # fails before simulating anything ends by itself and is caught here.
    while not (started.exists() and started.read_text()) and proc.poll() is None:
        time.sleep(0.05)
    assert proc.poll() is None, proc.communicate()[1]
    os.killpg(proc.pid, signal.SIGINT)
    # Read to the end of the stream: every process that holds it (workers, Python's resource
    # tracker, which may write after the run itself has ended) has closed it by then.
    _, text = proc.communicate()
    status = proc.returncode
    assert status == 130, text
    assert "Traceback" not in text and "KeyboardInterrupt" not in text, text
    assert text.rstrip().splitlines()[-1] == "burstloc: interrupted", text
    assert out.read_text() == '{"kept": true}\n'
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".results")] == []
    # The work stops: no simulation under way is finished (nor cached) after Ctrl-C.
    assert list(cache.rglob("*.npz")) == []


def test_a_closed_stdout_ends_quietly(tiny: Path, tmp_path: Path) -> None:
    proc = subprocess.Popen(
        [*BURSTLOC, "simulate", str(tiny), "--pipe", "A", *SHORT, "--out", str(tmp_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=_env(None),
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # like `burstloc ... | head -0`
    stderr = proc.stderr.read().decode()
    assert proc.wait() == 141, stderr
    assert stderr == ""


# --- 7. every error inside the contract -----------------------------------------------------


def test_an_unreachable_scheduler_is_an_error_even_when_everything_is_cached(
    tiny: Path, tmp_path: Path
) -> None:
    cache = tmp_path / "cache"
    args = ("simulate", tiny, "--pipe", "A", *SHORT, "--out", tmp_path / "o", "--cache-dir", cache)
    assert burstloc(*args).returncode == 0
    proc = burstloc(*args, "--scheduler", "tcp://127.0.0.1:9")
    refused(proc, "cannot reach the Dask scheduler 'tcp://127.0.0.1:9'")


@pytest.mark.parametrize(
    "option",
    [
        ["--localization-interval", str(2**64), "--threshold", "0.5"],
        ["--phases", str(2**64)],
    ],
)
def test_huge_counts_are_configuration_errors(
    tiny: Path, tmp_path: Path, option: list[str]
) -> None:
    args = ["--pipes", "A", "--capture-interval", "0.2", "--quiet", "--localizer", "paper"]
    proc = burstloc("evaluate", tiny, *args, *option, cache=tmp_path)
    refused(proc, option[0].lstrip("-").replace("-", "_"))
