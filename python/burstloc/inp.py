"""EPANET INP files read as text, without WNTR: structure checks, pipe IDs, a fingerprint.

* :func:`pipe_names_in_file` checks a file's structure (UTF-8 text, sections, field counts,
  numbers, IDs, node references, at least one junction and one source, positive pipe lengths
  and diameters) and returns its pipe IDs, cheaply; :func:`burstloc.network.load_network`
  runs the same checks before WNTR reads the file, so a malformed file is named with its line.
* :func:`network_hash` fingerprints a network file (its bytes): what a stored configuration
  is bound to.
* :func:`choose_pipes` checks a selection of pipes against a file's.
* :func:`junction_names_in_file` lists a file's junctions, and :func:`check_meters` is the one
  rule for meters: each is a junction of the network (``calibrate``, the signatures and the
  localization model with WNTR's list, a stored configuration with the file's).
"""

from __future__ import annotations

import hashlib
import math
import os
import time
from collections import OrderedDict
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from burstloc._validate import some_names
from burstloc.exceptions import ConfigError, NetworkError

__all__ = [
    "check_meters",
    "check_text",
    "choose_pipes",
    "decode",
    "file_key",
    "fingerprint",
    "junction_names_in_file",
    "known_hash",
    "network_hash",
    "node_line",
    "pipe_names_in_file",
    "read_bytes",
    "remember_hash",
    "settled",
]

#: Section headers EPANET 2.2 accepts (as WNTR reads them), and ``[END]``.
_SECTIONS = frozenset(
    f"[{name}]"
    for name in (  # noqa: SIM905 (one string reads better than 28 list items)
        "TITLE JUNCTIONS RESERVOIRS TANKS PIPES PUMPS VALVES EMITTERS CURVES PATTERNS ENERGY "
        "STATUS CONTROLS RULES DEMANDS QUALITY REACTIONS SOURCES MIXING OPTIONS TIMES REPORT "
        "COORDINATES VERTICES LABELS BACKDROP TAGS END"
    ).split()
)
#: Per section: the minimum number of fields of a data line and the fields that must be numbers.
_FIELDS: dict[str, tuple[int, tuple[int, ...]]] = {
    "[JUNCTIONS]": (2, (1, 2)),
    "[RESERVOIRS]": (2, (1,)),
    "[TANKS]": (6, (1, 2, 3, 4, 5, 6)),
    "[PIPES]": (6, (3, 4, 5, 6)),
    "[PUMPS]": (4, ()),
    "[VALVES]": (6, (3,)),
    "[EMITTERS]": (2, (1,)),
    "[DEMANDS]": (2, (1,)),
    "[COORDINATES]": (3, (1, 2)),
    "[VERTICES]": (3, (1, 2)),
}
_NODE_SECTIONS = ("[JUNCTIONS]", "[RESERVOIRS]", "[TANKS]")
_LINK_SECTIONS = ("[PIPES]", "[PUMPS]", "[VALVES]")
_PIPE_STATUS = frozenset({"OPEN", "CLOSED", "CV"})


@dataclass(frozen=True)
class _Row:
    section: str
    line: int
    fields: list[str]


def _section_name(header: str) -> str:
    """Map a header to its canonical name, forgiving a missing or extra S as WNTR does."""
    for candidate in (header, header.replace("]", "S]"), header.replace("S]", "]")):
        if candidate in _SECTIONS:
            return candidate
    return header


def read_bytes(path: str | os.PathLike[str]) -> bytes:
    """The bytes of a network file: the one place an INP file is opened.

    Raises:
        NetworkError: the file is missing or cannot be read.
    """
    try:
        return Path(path).read_bytes()
    except FileNotFoundError:
        raise NetworkError(f"network file not found: {os.fspath(path)}") from None
    except OSError as exc:
        raise NetworkError(f"cannot read network file {os.fspath(path)}: {exc.strerror}") from None


def decode(path: str | os.PathLike[str], data: bytes) -> str:
    """The text of ``data`` (the bytes of the INP file ``path``).

    Raises:
        NetworkError: not UTF-8, naming the line.
    """
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        bad_line = data.count(b"\n", 0, exc.start) + 1
        raise NetworkError(
            f"{os.fspath(path)}:{bad_line}: not UTF-8 text (byte 0x{data[exc.start]:02x}); save "
            "the file as UTF-8"
        ) from None


def fingerprint(data: bytes) -> str:
    """``"sha256:<hex>"`` of a network file's bytes (:func:`network_hash`)."""
    return f"sha256:{hashlib.sha256(data).hexdigest()}"


def _rows(path: Path, text: str | None = None) -> Iterator[_Row]:
    """Yield the data lines of an INP file (its ``text`` when given, else read) with their
    section and 1-based line number."""
    if text is None:
        text = decode(path, read_bytes(path))
    yield from _section_rows(text.splitlines(), path)


def _section_rows(lines: Iterable[str], path: str | os.PathLike[str]) -> Iterator[_Row]:
    """The data lines of an INP file's text (``lines``, from its first) with their section
    (canonical name: ``[TIME]`` is ``[TIMES]``, as WNTR reads it) and 1-based line number,
    comments left out, up to ``[END]``.

    Raises:
        NetworkError: an unknown section, or data before any section, naming ``path``'s line.
    """
    section: str | None = None
    for number, raw in enumerate(lines, start=1):
        line = raw.split(";", 1)[0].strip()
        if not line:
            continue
        if line.startswith("["):
            header = _section_name(line.split()[0].upper())
            if header not in _SECTIONS:
                raise NetworkError(f"{path}:{number}: unknown INP section {header}")
            if header == "[END]":
                return
            section = header
            continue
        if section is None:
            raise NetworkError(f"{path}:{number}: data before any [SECTION] header: {line!r}")
        yield _Row(section, number, line.split())


def _lint(path: Path, text: str | None = None) -> list[str]:
    """Check the structure WNTR's reader does not report with a line number; return the pipes
    (of ``text``, the file's, when given; else the file is read)."""
    nodes: dict[str, int] = {}
    pipes: list[str] = []
    links: dict[str, int] = {}
    refs: list[tuple[_Row, str]] = []
    sources = 0
    for row in _rows(path, text):
        spec = _FIELDS.get(row.section)
        if spec is None:
            continue
        minimum, numeric = spec
        where = f"{path}:{row.line}"
        if len(row.fields) < minimum:
            raise NetworkError(
                f"{where}: {row.section} line needs at least {minimum} fields, "
                f"got {len(row.fields)}: {' '.join(row.fields)!r}"
            )
        for i in numeric:
            if i < len(row.fields):
                try:
                    float(row.fields[i])
                except ValueError:
                    raise NetworkError(
                        f"{where}: {row.section} field {i + 1} of {row.fields[0]!r} is not a "
                        f"number: {row.fields[i]!r}"
                    ) from None
        name = row.fields[0]
        if row.section in _NODE_SECTIONS or row.section in _LINK_SECTIONS:
            table = nodes if row.section in _NODE_SECTIONS else links
            if name in table:
                raise NetworkError(
                    f"{where}: duplicate ID {name!r} (first defined at line {table[name]})"
                )
            table[name] = row.line
        if row.section in _LINK_SECTIONS:
            refs.extend((row, node) for node in row.fields[1:3])
        sources += row.section in ("[RESERVOIRS]", "[TANKS]")
        if row.section == "[PIPES]":
            _check_pipe_size(row, where)
            pipes.append(name)
            if len(row.fields) >= 8 and row.fields[7].upper() not in _PIPE_STATUS:
                raise NetworkError(f"{where}: pipe {name!r} has unknown status {row.fields[7]!r}")
    for row, node in refs:
        if node not in nodes:
            raise NetworkError(
                f"{path}:{row.line}: link {row.fields[0]!r} refers to unknown node {node!r}"
            )
    if len(nodes) == sources:
        raise NetworkError(f"{path}: no junctions: the network needs at least one junction")
    if sources == 0:
        raise NetworkError(f"{path}: no source: the network needs a reservoir or a tank")
    return pipes


def _check_pipe_size(row: _Row, where: str) -> None:
    """A pipe's length and diameter are positive finite numbers."""
    for index, what in ((3, "length"), (4, "diameter")):
        value = float(row.fields[index])
        if not (math.isfinite(value) and value > 0):
            raise NetworkError(
                f"{where}: pipe {row.fields[0]!r} has {what} {row.fields[index]} (must be > 0)"
            )


def check_text(path: str | os.PathLike[str], text: str) -> list[str]:
    """:func:`pipe_names_in_file` of ``text``, the INP file ``path``'s text (not read again).

    Raises:
        NetworkError: the text is malformed (naming file and line).
    """
    return _lint(Path(path), text)


def pipe_names_in_file(path: str | os.PathLike[str]) -> list[str]:
    """Return the pipe IDs of an INP file in file order, without building a network model.

    The file's structure is checked as :func:`burstloc.network.load_network` checks it before
    WNTR reads it (sections, field counts, numbers, IDs, node references), cheaply and without WNTR.

    Raises:
        NetworkError: the file is missing or malformed (naming file and line).
    """
    return list(_once(_lint, Path(path)))


def junction_names_in_file(path: str | os.PathLike[str]) -> list[str]:
    """Return the junction IDs of an INP file in file order, without building a network model
    (the file checked as :func:`pipe_names_in_file` checks it).

    Raises:
        NetworkError: the file is missing or malformed (naming file and line).
    """
    return list(_once(_junctions, Path(path)))


def _junctions(file: Path, text: str) -> list[str]:
    _lint(file, text)
    return [row.fields[0] for row in _rows(file, text) if row.section == "[JUNCTIONS]"]


#: What :func:`_once` read, by reader, file and fingerprint (the most recent last).
_NAMES: OrderedDict[tuple[str, str, str], tuple[str, ...]] = OrderedDict()


def _once(read: Callable[[Path, str], list[str]], file: Path) -> tuple[str, ...]:
    """``read(file, text)``, once per content of the file in this process (each monitor of an
    evaluation checks its configuration's meters against the file: 57 ms on L-TOWN). The file
    is opened at most once, and not at all when its fingerprint and ``read``'s answer are
    known (:func:`network_hash`)."""
    key = file_key(file)
    digest = known_hash(key)
    text = None
    if digest is None:
        read_at = time.time_ns()
        data = read_bytes(file)
        digest = fingerprint(data)
        remember_hash(key, digest, read_at)
        text = decode(file, data)
    slot = (read.__name__, str(file), digest)
    if slot not in _NAMES:
        if text is None:
            text = decode(file, read_bytes(file))
        _NAMES[slot] = tuple(read(file, text))
        while len(_NAMES) > 16:
            _NAMES.popitem(last=False)
    _NAMES.move_to_end(slot)
    return _NAMES[slot]


def node_line(path: str | os.PathLike[str], node: str) -> int | None:
    """The 1-based line of an INP file that defines ``node`` (a junction, reservoir or tank);
    ``None`` when the file does not (a node burstloc added) or cannot be read."""
    try:
        return next(
            (
                row.line
                for row in _rows(Path(path))
                if row.section in _NODE_SECTIONS and row.fields[0] == node
            ),
            None,
        )
    except NetworkError:
        return None


def check_meters(
    meters: Sequence[str],
    junctions: Sequence[str],
    network: str | os.PathLike[str],
    error: type[ValueError] = NetworkError,
) -> list[str]:
    """Return ``meters`` as a list if each is one of ``junctions`` (those of ``network``).

    Raises:
        NetworkError: ``N meter(s) [...] are not junctions of NETWORK``, naming the first few
            and counting the rest (or ``error``: a :class:`~burstloc.exceptions.ConfigError`
            where the meters are a parameter, as in ``calibrate``).
    """
    known = set(junctions)
    unknown = [m for m in meters if m not in known]
    if unknown:
        raise error(
            f"{len(unknown)} meter(s) {some_names(unknown)} are not junctions of "
            f"{os.fspath(network)}"
        )
    return list(meters)


def choose_pipes(
    known: Sequence[str], pipes: Sequence[str] | None, source: str | os.PathLike[str]
) -> list[str]:
    """The pipes to burst: ``pipes`` (default: every one of ``known``), checked against the
    network read from ``source``.

    Raises:
        NetworkError: a pipe the network does not have, or no pipe at all.
        ConfigError: a pipe listed twice.
    """
    chosen = list(known if pipes is None else pipes)
    unknown = [p for p in chosen if p not in known]
    where = os.fspath(source)
    if unknown:
        raise NetworkError(f"unknown pipe(s) {unknown} in {where}; pipes: {', '.join(known)}")
    if not chosen:
        raise NetworkError(f"no pipes to burst in {where}")
    if len(set(chosen)) != len(chosen):
        raise ConfigError(f"pipes listed more than once: {chosen}")
    return chosen


#: How long (ns) before a file was read its modification time must lie for what was read to
#: be trusted while the file's times and size are unchanged: a file written again within its
#: file system's timestamp granularity (up to 2 s, FAT) can keep them (git's "racy" files).
SETTLED_NS = 2_000_000_000

FileKey = tuple[str, int, int, int]
"""A file's real path, modification and change times (ns) and size (:func:`file_key`)."""

#: Fingerprints of files this process read, and when it read them, by :func:`file_key` (the
#: most recent last).
_HASHES: OrderedDict[FileKey, tuple[str, int]] = OrderedDict()


def file_key(path: str | os.PathLike[str]) -> FileKey | None:
    """The file's real path, modification and change times (ns) and size; ``None`` when it
    cannot be read. A file written again has another key, unless it was written within the
    timestamp granularity of its file system (:func:`settled`)."""
    try:
        stat = os.stat(path)
    except OSError:
        return None
    return (os.path.realpath(path), stat.st_mtime_ns, stat.st_ctime_ns, stat.st_size)


def settled(key: FileKey, read_at: int) -> bool:
    """Whether what was read of the file of ``key`` at ``read_at`` (``time.time_ns()`` before
    the read) is its content while its key is ``key``: it was last written
    :data:`SETTLED_NS` before."""
    return key[1] < read_at - SETTLED_NS


def remember_hash(key: FileKey | None, digest: str, read_at: int) -> None:
    """Keep ``digest`` as the fingerprint of the file of ``key`` (:func:`file_key`, taken
    before the file was read at ``read_at``) for :func:`network_hash`."""
    if key is not None:
        _HASHES[key] = (digest, read_at)
        _HASHES.move_to_end(key)
        while len(_HASHES) > 64:
            _HASHES.popitem(last=False)


def known_hash(key: FileKey | None) -> str | None:
    """The fingerprint of the file of ``key`` if this process read it and it is
    :func:`settled`; else ``None``."""
    entry = _HASHES.get(key) if key is not None else None
    if entry is None or key is None or not settled(key, entry[1]):
        return None
    return entry[0]


def network_hash(path: str | os.PathLike[str]) -> str:
    """Fingerprint of a network file: ``"sha256:<hex>"`` of its bytes (no model is built),
    read once per process while the file's times and size are unchanged (:func:`settled`; a
    file read by :func:`burstloc.network.read_network` is not read again).

    Raises:
        NetworkError: the file cannot be read.
    """
    key = file_key(path)
    digest = known_hash(key)
    if digest is None:
        read_at = time.time_ns()
        digest = fingerprint(read_bytes(path))
        remember_hash(key, digest, read_at)
    return digest
