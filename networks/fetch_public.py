"""Fetch EPANET's public example networks (Net1, Net2, Net3, Anytown) into ``networks/public/``.

The four INP files ship inside the ``epyt`` wheel on PyPI (EPyT, the EPANET-Python Toolkit,
EUPL-1.2; the networks themselves come from EPANET's examples and the ASCE Task Committee's
benchmark set). They are third-party files, so they are not committed: this script downloads
the pinned wheel (pinned version, URL and SHA-256), extracts the four files and the wheel's
licence, checks each file's pinned SHA-256 and writes ``networks/public/MANIFEST.json``. The
wheel is kept beside them, so a later run (or the tests) can re-extract with no connection.

Run from the repository root (``make networks`` does; standard library only)::

    python networks/fetch_public.py                # fetch if missing or changed, else nothing
    python networks/fetch_public.py --check        # exit 1 unless every file is as pinned
    python networks/fetch_public.py --wheel W.whl  # extract from a wheel downloaded by hand
    python networks/fetch_public.py --library      # also the wheel's whole network library

``--library [DIR]`` extracts every INP file of the wheel (``epyt/networks/``: L-TOWN, the
Kentucky networks KY1-KY15, BWSN, Richmond, exnet, MICROPOLIS, ...) into ``DIR`` (default
``networks/public/library/``, gitignored: never commit these files; the Kentucky networks are
for non-commercial research use only) with ``LIBRARY.json`` recording, per file, its path in the
wheel, its SHA-256 and its terms. ``benches/bench_library.py`` sweeps them.

A file whose hash differs from the pin is refused by name; nothing partial is left behind.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import sys
import tempfile
import urllib.error
import urllib.request
import zipfile
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
#: Where the networks go (gitignored).
PUBLIC = HERE / "public"

#: The pinned wheel: version, file name, PyPI URL and SHA-256 (as PyPI lists it).
VERSION = "2.3.5.3"
WHEEL = f"epyt-{VERSION}-py3-none-any.whl"
URL = (
    "https://files.pythonhosted.org/packages/a1/ac/"
    f"a742e9bb4408d70d8aba563c6ab4a1a28f3411293b59dbf058d344175cec/{WHEEL}"
)
WHEEL_SHA256 = "6665a5ab3168c41257dfba2ef1aee262172051d396cf807c1978e6d0ea359ec6"
LICENCE = "EUPL-1.2"
LICENCE_IN_WHEEL = f"epyt-{VERSION}.dist-info/licenses/LICENSE.md"
LICENCE_FILE = "LICENSE-epyt.md"
MANIFEST = "MANIFEST.json"
#: How long to wait for PyPI (s).
TIMEOUT = 60.0


@dataclass(frozen=True)
class PublicNetwork:
    """One network of the set: our file name, its path inside the wheel, its pinned SHA-256,
    and where it comes from upstream."""

    name: str
    member: str
    sha256: str
    origin: str


_DIR = "epyt/networks/asce-tf-wdst"
NETWORKS = (
    PublicNetwork(
        "Net1.inp",
        f"{_DIR}/Net1.inp",
        "2041078b222711422fa79970f5e3a203fd170117e19e7af39627b2a3e5424a13",
        "EPANET example network 1 (US EPA)",
    ),
    PublicNetwork(
        "Net2.inp",
        f"{_DIR}/Net2.inp",
        "c795047e5475b41565e1606c1f229e6e649851f6c8eb66373d248466baaf03a9",
        "EPANET example network 2 (US EPA)",
    ),
    PublicNetwork(
        "Net3.inp",
        f"{_DIR}/Net3.inp",
        "7d3ee9beec357dbb4b26d21a135fde7d500e53e951e6eab966e58df93301c207",
        "EPANET example network 3 (US EPA)",
    ),
    PublicNetwork(
        "Anytown.inp",
        f"{_DIR}/Anytown.inp",
        "0090196614412ca5f5a2c29286911698a0fe9a83f335fabe63875afc50bbe01c",
        "Anytown (Walski et al. 1987), as in the ASCE TF-WDST benchmark set (EPANET format)",
    ),
)


class FetchError(RuntimeError):
    """The networks cannot be fetched or do not match their pins; the message says which file
    and what to do."""


def sha256_of(path: Path) -> str:
    """The SHA-256 (hex) of a file's bytes."""
    digest = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def verify(path: Path, expected: str) -> None:
    """Raise :class:`FetchError` naming ``path`` unless it exists with SHA-256 ``expected``."""
    if not path.is_file():
        raise FetchError(f"{path} is missing: run `make networks`")
    actual = sha256_of(path)
    if actual != expected:
        raise FetchError(
            f"{path} has SHA-256 {actual}, expected {expected}: the file is not the pinned "
            "one; delete it and run `make networks`"
        )


def check(out: Path = PUBLIC) -> None:
    """Raise :class:`FetchError` unless every network in ``out`` is present and as pinned."""
    for net in NETWORKS:
        verify(out / net.name, net.sha256)
    if not (out / MANIFEST).is_file():
        raise FetchError(f"{out / MANIFEST} is missing: run `make networks`")


def download(dest: Path, url: str = URL, timeout: float = TIMEOUT) -> Path:
    """Download the pinned wheel to ``dest`` (a directory), check its SHA-256, return its path."""
    target = dest / WHEEL
    partial = dest / (WHEEL + ".part")
    try:
        with urllib.request.urlopen(url, timeout=timeout) as response, partial.open("wb") as f:
            shutil.copyfileobj(response, f)
    except (urllib.error.URLError, OSError) as exc:
        partial.unlink(missing_ok=True)
        raise FetchError(
            f"cannot download {url} ({exc}): connect to the internet and run `make networks`, "
            f"or download {WHEEL} (pip download epyt=={VERSION} --no-deps) and run "
            f"`python networks/fetch_public.py --wheel PATH`"
        ) from exc
    try:
        verify(partial, WHEEL_SHA256)
    except FetchError:
        partial.unlink(missing_ok=True)
        raise FetchError(f"{url}: the downloaded wheel is not the pinned one") from None
    os.replace(partial, target)
    return target


def extract(wheel: Path, out: Path = PUBLIC) -> list[Path]:
    """Extract the four networks and the licence from ``wheel`` into ``out``, check every hash
    and write the manifest; return the written network paths. Nothing is replaced unless every
    file checks out."""
    verify(wheel, WHEEL_SHA256)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out, prefix=".fetch-") as tmp:
        staging = Path(tmp)
        with zipfile.ZipFile(wheel) as archive:
            for net in NETWORKS:
                data = archive.read(net.member)
                actual = hashlib.sha256(data).hexdigest()
                if actual != net.sha256:
                    raise FetchError(
                        f"{net.member} in {wheel} has SHA-256 {actual}, expected {net.sha256}"
                    )
                (staging / net.name).write_bytes(data)
            (staging / LICENCE_FILE).write_bytes(archive.read(LICENCE_IN_WHEEL))
        (staging / MANIFEST).write_text(json.dumps(manifest(), indent=2) + "\n", "utf-8")
        for name in [net.name for net in NETWORKS] + [LICENCE_FILE, MANIFEST]:
            os.replace(staging / name, out / name)
    return [out / net.name for net in NETWORKS]


def manifest() -> dict[str, object]:
    """What ``MANIFEST.json`` records: the source wheel and, per network, where it comes from."""
    return {
        "source": {"package": "epyt", "version": VERSION, "wheel": WHEEL, "url": URL},
        "wheel_sha256": WHEEL_SHA256,
        "licence": LICENCE,
        "licence_file": LICENCE_FILE,
        "networks": [
            {
                "name": net.name,
                "wheel": WHEEL,
                "url": URL,
                "path_in_wheel": net.member,
                "sha256": net.sha256,
                "licence": LICENCE,
                "upstream": net.origin,
            }
            for net in NETWORKS
        ],
    }


def fetch(out: Path = PUBLIC, wheel: Path | None = None) -> str:
    """Make ``out`` hold the pinned networks: nothing if it already does, else extract from
    ``wheel``, the wheel kept in ``out``, or a fresh download. Return what was done."""
    try:
        check(out)
        return f"{out}: the public networks are present and as pinned"
    except FetchError:
        pass
    if wheel is None:
        kept = out / WHEEL
        out.mkdir(parents=True, exist_ok=True)
        wheel = kept if kept.is_file() and sha256_of(kept) == WHEEL_SHA256 else download(out)
    extract(wheel, out)
    if wheel.resolve() != (out / WHEEL).resolve():
        shutil.copyfile(wheel, out / WHEEL)  # kept: a later run re-extracts offline
    return f"{out}: extracted {', '.join(n.name for n in NETWORKS)} from {wheel.name}"


#: Where ``--library`` extracts the wheel's network library (in ``networks/public/``, gitignored).
LIBRARY = PUBLIC / "library"
LIBRARY_MANIFEST = "LIBRARY.json"
_LIBRARY_ROOT = "epyt/networks/"
#: The terms recorded per file: the Kentucky networks' own, else the wheel's.
KY_TERMS = (
    "Kentucky Water Distribution System research database (University of Kentucky): "
    "non-commercial research use only; do not redistribute or commit"
)
WHEEL_TERMS = f"as distributed in the epyt wheel ({LICENCE}); the publishing authors' terms apply"


def _terms(member: str) -> str:
    return KY_TERMS if Path(member).name.lower().startswith("ky") else WHEEL_TERMS


def extract_library(wheel: Path, out: Path = LIBRARY) -> list[Path]:
    """Extract every INP file under ``epyt/networks/`` of the pinned ``wheel`` into ``out``
    (its folders kept) with the wheel's licence and ``LIBRARY.json`` (source, and per file its
    path in the wheel, SHA-256 and terms); return the written paths."""
    verify(wheel, WHEEL_SHA256)
    out.mkdir(parents=True, exist_ok=True)
    written, records = [], []
    with zipfile.ZipFile(wheel) as archive:
        members = sorted(
            m
            for m in archive.namelist()
            if m.startswith(_LIBRARY_ROOT) and m.lower().endswith(".inp")
        )
        for member in members:
            data = archive.read(member)
            target = out / member[len(_LIBRARY_ROOT) :]
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
            written.append(target)
            records.append(
                {
                    "path": target.relative_to(out).as_posix(),
                    "path_in_wheel": member,
                    "sha256": hashlib.sha256(data).hexdigest(),
                    "terms": _terms(member),
                }
            )
        (out / LICENCE_FILE).write_bytes(archive.read(LICENCE_IN_WHEEL))
    document = {
        "source": {"package": "epyt", "version": VERSION, "wheel": WHEEL, "url": URL},
        "wheel_sha256": WHEEL_SHA256,
        "licence": LICENCE,
        "licence_file": LICENCE_FILE,
        "networks": records,
    }
    (out / LIBRARY_MANIFEST).write_text(json.dumps(document, indent=2) + "\n", "utf-8")
    return written


def main(argv: list[str] | None = None) -> int:
    """Fetch (or with ``--check`` verify) the public networks; return the exit status."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="verify only, download nothing")
    parser.add_argument("--wheel", type=Path, help=f"extract from this {WHEEL}, no download")
    parser.add_argument("--out", type=Path, default=PUBLIC, help="target directory")
    parser.add_argument(
        "--library",
        nargs="?",
        type=Path,
        const=LIBRARY,
        default=None,
        metavar="DIR",
        help=f"also extract the wheel's whole network library (default {LIBRARY})",
    )
    args = parser.parse_args(argv)
    try:
        if args.check:
            check(args.out)
            print(f"{args.out}: the public networks are present and as pinned")
        else:
            print(fetch(args.out, args.wheel))
            if args.library is not None:
                wheel = args.wheel if args.wheel is not None else args.out / WHEEL
                files = extract_library(wheel, args.library)
                print(f"{args.library}: extracted {len(files)} INP files from {wheel.name}")
    except FetchError as exc:
        print(f"fetch_public: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
