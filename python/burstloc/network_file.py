"""An EPANET INP file read once into a :class:`Network`, and kept per process.

:func:`read_network` opens the file once (:func:`burstloc.inp.read_bytes`): its structure is
checked, it is hashed and WNTR reads its hydraulic text; a process keeps the networks it read
while their files are unchanged, so a worker process sent a path reads the file once. The CLI
and the public API turn a path into a :class:`Network` at their edge (:func:`as_network`) and
pass it down; :func:`load_network` gives a model the caller may change (a copy). WNTR is
imported on first use (:func:`import_wntr`); TSNet never. The rest of what is done with a
network (its steady state, flow directions, a split pipe) is :mod:`burstloc.network`.
"""

from __future__ import annotations

import copy
import os
import re
import tempfile
import time
import warnings
from collections import OrderedDict
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Union

from burstloc._diagnostics import Recording, recording
from burstloc.exceptions import NetworkError, SimulatorMissingError
from burstloc.inp import (
    FileKey,
    check_text,
    decode,
    file_key,
    fingerprint,
    network_hash,
    read_bytes,
    remember_hash,
    settled,
)
from burstloc.inp_hydraulic import hydraulic_text

if TYPE_CHECKING:
    from wntr.network import WaterNetworkModel

__all__ = [
    "KEPT_NETWORKS",
    "Network",
    "NetworkSource",
    "as_network",
    "identify",
    "import_wntr",
    "load_network",
    "read_network",
]

_WNTR_LINE = re.compile(r"at line (\d+)")


def import_wntr() -> Any:
    """Import WNTR without its import-time deprecation noise (pkg_resources).

    Raises:
        SimulatorMissingError: WNTR is not installed (it comes with the ``sim`` extra).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        # setuptools 80 warns that pkg_resources (which WNTR 1.3 imports) is deprecated
        warnings.filterwarnings("ignore", "pkg_resources is deprecated", UserWarning)
        try:
            import wntr
        except ImportError as exc:
            raise SimulatorMissingError(exc) from exc
    return wntr


@dataclass(frozen=True, eq=False)
class Network:
    """An INP file read once: everything below the CLI and the public API takes this, never
    the path.

    Attributes:
        path: the file as given.
        hash: ``"sha256:<hex>"`` of the bytes read (:func:`burstloc.inp.network_hash`).
        model: WNTR's model of those bytes; shared, never to be changed (:meth:`editable`
            gives a copy to change).
        pipes: the pipe IDs in file order.
        junctions: the junction IDs in file order.
        recorded: what WNTR printed, logged and warned while it read the file
            (:func:`burstloc._diagnostics.recording`), for a caller that replays it.

    A pickled network (sent to a worker process) carries its path and hash only: the worker
    reads the file once (:func:`read_network`) and refuses it if its bytes changed.
    """

    path: str
    hash: str
    model: WaterNetworkModel = field(repr=False)
    pipes: tuple[str, ...] = field(repr=False)
    junctions: tuple[str, ...] = field(repr=False)
    recorded: Recording = field(repr=False, default_factory=Recording)

    def editable(self) -> WaterNetworkModel:
        """A copy of :attr:`model` for the caller to change."""
        return copy.deepcopy(self.model)

    def __reduce__(self) -> tuple[Any, tuple[str, str]]:
        return (_reopen, (self.path, self.hash))


#: A network as the public API takes it: a :class:`Network` or the path of its INP file.
NetworkSource = Union[Network, str, "os.PathLike[str]"]

#: Networks read in this process and when (the most recently used last), by
#: :func:`burstloc.inp.file_key`: a file written again is read afresh.
_READ: OrderedDict[FileKey, tuple[Network, int]] = OrderedDict()
#: Networks kept per process.
KEPT_NETWORKS = 4


def read_network(path: str | os.PathLike[str]) -> Network:
    """Read an EPANET INP file once into a :class:`Network`, kept for this process while the
    file's times and size are unchanged: a second call reads nothing (a file written less than
    :data:`burstloc.inp.SETTLED_NS` before it was read is hashed again, not parsed again).

    The file is opened once (:func:`burstloc.inp.read_bytes`): its structure is checked
    (:func:`burstloc.inp.check_text`), it is hashed, and WNTR reads its hydraulic text
    (:func:`burstloc.inp_hydraulic.hydraulic_text`) from a temporary copy.

    Raises:
        NetworkError: the file is missing or malformed; the message names the file and, when
            the problem is on one line, the line number (``FILE:LINE: problem``).
    """
    file, given = Path(path), os.fspath(path)
    key = file_key(file)
    if key is None:
        return _read_network(given, file)  # names the problem (missing, unreadable)
    kept = _READ.get(key)
    if kept is not None:
        network, read_at = kept
        same = settled(key, read_at)
        if not same:  # written just before it was read: its bytes compared, not parsed again
            read_at = time.time_ns()
            same = network_hash(file) == network.hash
            if same:
                _READ[key] = (network, read_at)
        if same:
            _READ.move_to_end(key)
            return network if network.path == given else replace(network, path=given)
    read_at = time.time_ns()
    network = _read_network(given, file)
    remember_hash(key, network.hash, read_at)
    _READ[key] = (network, read_at)
    while len(_READ) > KEPT_NETWORKS:
        _READ.popitem(last=False)
    return network


def _read_network(given: str, file: Path) -> Network:
    wntr = import_wntr()
    data = read_bytes(file)
    text = decode(file, data)
    pipes = check_text(file, text)  # names a malformed file's line before WNTR reads it
    hydraulic = hydraulic_text(file, text)
    with tempfile.TemporaryDirectory(prefix="burstloc-inp-") as tmp:
        read = Path(tmp) / file.name
        read.write_text(text if hydraulic is None else hydraulic, encoding="utf-8")
        with recording() as record:
            wn = _read(wntr, read, file)
    wn.name = str(file)
    return Network(
        given,
        fingerprint(data),
        wn,
        tuple(pipes),
        tuple(wn.junction_name_list),
        record,
    )


def _reopen(path: str, digest: str) -> Network:
    """A pickled :class:`Network`, read again (once per process)."""
    network = read_network(path)
    if network.hash != digest:
        raise NetworkError(
            f"network file {path} changed ({network.hash}) since it was read ({digest})"
        )
    return network


def as_network(network: NetworkSource, *, diagnostics: bool = False) -> Network:
    """``network`` itself, or the file at that path read (:func:`read_network`): where the
    public API turns a path into the network it passes down.

    ``diagnostics``: what WNTR printed, logged and warned while reading the file reaches the
    :func:`~burstloc._diagnostics.capture_diagnostics` block running even when the file was
    read before (replayed): a simulation's record does not depend on what the process read
    before it.
    """
    if not diagnostics:
        return network if isinstance(network, Network) else read_network(network)
    with recording() as now:
        read = as_network(network)
    if not now.events:  # read before (at the edge, or for an earlier simulation)
        read.recorded.replay()
    return read


def identify(network: NetworkSource) -> tuple[str, str]:
    """``(path, hash)`` of a network, or of an INP file without building its model
    (:func:`burstloc.inp.network_hash`: what the live path, which never loads WNTR, checks)."""
    if isinstance(network, Network):
        return network.path, network.hash
    return os.fspath(network), network_hash(network)


def load_network(network: NetworkSource) -> WaterNetworkModel:
    """A WNTR ``WaterNetworkModel`` of a network or INP file, for the caller to change (a copy
    of :attr:`Network.model`; the file is read once per process, :func:`read_network`).

    Raises:
        NetworkError: the file is missing or malformed; the message names the file and, when
            the problem is on one line, the line number (``FILE:LINE: problem``).
    """
    return as_network(network).editable()


#: Where the warnings WNTR gives while reading a file are registered (as a module's own
#: ``__warningregistry__``: a warning the filters show once is shown once).
_WARNED: dict[Any, Any] = {}


def _read(wntr: Any, read: Path, file: Path) -> WaterNetworkModel:
    """WNTR's model of ``read`` (the text of ``file``); its errors and warnings name ``file``
    (and the line)."""
    try:
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            wn = wntr.network.WaterNetworkModel(str(read))
        for w in said:  # said again, naming the file read, not its temporary copy
            text = str(w.message).replace(str(read), str(file))
            warnings.warn_explicit(text, w.category, w.filename, w.lineno, registry=_WARNED)
        return wn
    except Exception as exc:  # WNTR raises many types for bad input; name file and line
        detail = str(exc)
        line = None
        cause: BaseException | None = exc
        while cause is not None:
            match = _WNTR_LINE.search(str(cause))
            if match:
                line = match.group(1)
                detail = str(cause)
            cause = cause.__cause__
        where = f"{file}:{line}" if line else f"{file}"
        detail = detail.replace(str(read), str(file))
        raise NetworkError(f"{where}: malformed INP file: {type(exc).__name__}: {detail}") from exc
