"""The per-call cost of the stable ABI: ``Cusum.update`` from the abi3 extension and from one built
for this interpreter only, in one process, on fresh data.

Usage: ``.venv/bin/python benches/bench_abi3.py [--samples N] [--repeat R]``. It builds both
extensions from the sources with cargo (``crates/cpd-py`` with its default ``abi3`` feature, and
with ``--no-default-features``), for this CPU like ``make setup`` (``$EXT_RUSTFLAGS``, default
``-C target-cpu=native``), in ``target-abi3/`` (a few minutes the first time), loads both into
this process and times, alternately, ``Cusum.update`` once per sample from a Python ``for`` loop
on a trace neither has seen (``bench_detectors.fresh_trace``, a new seed per run), beside a bare
C-function call (``math.fabs``), the floor of any per-call API. Each figure is the best of
``--repeat`` runs; the script prints the load average, the figures and the ratio.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path
from types import ModuleType

from bench_detectors import CUSUM, per_call

REPO = Path(__file__).resolve().parents[1]
TARGET = REPO / "target-abi3"


def build(abi3: bool) -> Path:
    """Build the extension (abi3 or for this interpreter) and return its file."""
    command = ["cargo", "build", "--release", "-q", "-p", "cpd-py", "--target-dir", str(TARGET)]
    if not abi3:
        command.append("--no-default-features")
    flags = os.environ.get("EXT_RUSTFLAGS", "-C target-cpu=native")
    env = dict(os.environ, PYO3_PYTHON=sys.executable, RUSTFLAGS=flags)
    subprocess.run(command, check=True, env=env, cwd=REPO)
    suffix = ".abi3.so" if abi3 else sysconfig.get_config_var("EXT_SUFFIX")
    directory = TARGET / ("abi3" if abi3 else "specific")
    directory.mkdir(exist_ok=True)
    extension = directory / f"_core{suffix}"
    shutil.copyfile(TARGET / "release" / "libcpd_py.so", extension)
    return extension


def load(extension: Path) -> ModuleType:
    """Import an extension file as a module of its own."""
    spec = importlib.util.spec_from_file_location("burstloc._core", extension)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()

    modules = {"abi3 (Python >= 3.10)": load(build(True))}
    modules[f"for {sys.implementation.cache_tag} only"] = load(build(False))
    best = dict.fromkeys(modules, math.inf)
    floor = math.inf
    for _ in range(args.repeat):  # alternate, so both see the same machine
        for name, module in modules.items():
            made = module.Cusum(**CUSUM)
            best[name] = min(best[name], per_call(args.samples, lambda m=made: m.update, 1))
        floor = min(floor, per_call(args.samples, lambda: math.fabs, 1))

    print(f"Python {sys.version.split()[0]}, load average {os.getloadavg()[0]:.2f}, ", end="")
    print(f"{args.samples:,} samples, best of {args.repeat}")
    print(f"{'Cusum.update from Python, one call per sample':<48} ns/call  minus floor")
    for name, ns in best.items():
        print(f"  {name:<46} {ns:7.1f}  {ns - floor:7.1f}")
    print(f"  {'bare C call (math.fabs), the floor':<46} {floor:7.1f}")
    abi3, specific = best.values()
    print(f"abi3 / version-specific: {abi3 / specific:.3f}")


if __name__ == "__main__":
    main()
