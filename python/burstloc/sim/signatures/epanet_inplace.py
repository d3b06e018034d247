"""One EPANET project, opened once, in which a pipe is split by a bursting junction and restored.

:func:`burstloc.network.split_pipe` copies the whole WNTR model and every steady state writes and
parses an INP file: per pipe that is linear in the network's size, so a signature set (every pipe,
one steady state each) grows with the square of it. :class:`InPlaceSplitter` writes the model once
(as :func:`burstloc.network.steady_state` does: WNTR's INP writer in the model's INP units, the
demand model given, duration 0) with one spare junction and one spare closed pipe added, opens it
in EPANET 2.2's toolkit (the library WNTR bundles) and, per candidate burst, rewires the open
project the way WNTR's ``split_pipe`` edits its copy: the spare junction at ``fraction`` of the
pipe from its INP start node (elevation interpolated, a reservoir end taking the other end's
elevation), the pipe ending there with ``fraction`` of its length, the spare pipe carrying the rest
(same diameter, roughness, minor loss, check valve, status), an emitter at the junction. EPANET
solves the first time step from scratch (flows re-initialised, as ``ENsolveH`` does), the heads are
read, and the pipe is put back (the spare pipe closed, the emitter off). Nodes and links are never
added or deleted after the project is read, so EPANET's arrays keep their size. The solution is
EPANET's own, to its convergence tolerance; only the numbering of the spare elements differs from
the copied model's INP (checked against :func:`burstloc.network.split_pipe` + ``steady_state``
in ``tests/sim/test_epanet_inplace.py``).
"""

from __future__ import annotations

import ctypes
import os
import tempfile
from collections.abc import Sequence
from types import TracebackType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import ConfigError, NetworkError, SimulationError

__all__ = ["InPlaceSplitter", "split_elevation"]

# EPANET 2.2 toolkit codes (epanet2_enums.h)
_EN_ELEVATION, _EN_EMITTER, _EN_HEAD = 0, 3, 10
_EN_DIAMETER, _EN_LENGTH, _EN_ROUGHNESS, _EN_MINORLOSS, _EN_INITSTATUS = 0, 1, 2, 3, 4
_EN_CVPIPE, _EN_PIPE = 0, 1
_EN_UNCONDITIONAL = 0
_EN_INITFLOW = 10
_BURST_NODE, _BURST_LINK = "~burst~", "~burst~2"


class InPlaceSplitter:
    """Steady heads of a network with one pipe split by a bursting junction, without a copy.

    Use as a context manager (the EPANET project and its scratch files live until the block
    ends). ``wn`` is written out when the splitter opens and left as it was; ``engine`` is the
    demand model (``"PDD"`` or ``"DD"``) as in :func:`burstloc.network.steady_state`.

    Raises:
        ConfigError: an unknown ``engine``.
        NetworkError: no junction, or an element already named like the spare ones.
        SimulationError: EPANET refuses the model or fails to solve it.
    """

    def __init__(self, wn: Any, engine: str = "PDD") -> None:
        if engine.upper() not in ("PDD", "DD"):
            raise ConfigError(f"engine must be 'PDD' or 'DD', got {engine!r}")
        self._wn = wn
        self._engine = engine.upper()
        self._tmp: tempfile.TemporaryDirectory[str] | None = None
        self._en: Any = None
        self._ph: Any = None
        self._pipes = frozenset(wn.pipe_name_list)
        self._index_cache: dict[tuple[str, ...], list[int]] = {}

    # --- opening and closing -------------------------------------------------------------------
    def __enter__(self) -> InPlaceSplitter:
        from wntr.epanet.toolkit import ENepanet
        from wntr.epanet.util import FlowUnits, HydParam, from_si, to_si

        wn = self._wn
        units = str(wn.options.hydraulic.inpfile_units).upper()
        self._units = FlowUnits[units]
        self._from_si, self._to_si, self._param = from_si, to_si, HydParam
        anchor = wn.junction_name_list[0] if wn.num_junctions else None
        if anchor is None or _BURST_NODE in wn.node_name_list or _BURST_LINK in wn.link_name_list:
            raise NetworkError(
                f"the network needs a junction (and no element named {_BURST_NODE!r} or "
                f"{_BURST_LINK!r}) for the burst signatures"
            )
        self._tmp = tempfile.TemporaryDirectory(prefix="burstloc-inplace-")
        try:
            prefix = os.path.join(self._tmp.name, "model")
            self._write(prefix + ".inp", units, anchor)
            self._en = ENepanet(version=2.2)
            self._lib = self._en.ENlib
            self._ph = self._en._project
            self._lib.EN_createproject(ctypes.byref(self._ph))
            self._check(
                self._lib.EN_open(
                    self._ph,
                    (prefix + ".inp").encode(),
                    (prefix + ".rpt").encode(),
                    (prefix + ".bin").encode(),
                ),
                "opening the model",
            )
        except BaseException:
            self.close()
            raise
        return self

    def _write(self, path: str, units: str, anchor: str) -> None:
        """The model as :func:`burstloc.network.steady_state` writes it, plus the spare junction
        and the spare closed pipe (to ``anchor``); ``wn`` is left as it was."""
        from wntr.network.io import write_inpfile

        wn = self._wn
        hydraulic, times = wn.options.hydraulic, wn.options.time
        saved = (hydraulic.demand_model, times.duration)
        hydraulic.demand_model, times.duration = self._engine, 0
        wn.add_junction(_BURST_NODE, base_demand=0.0, elevation=wn.get_node(anchor).elevation)
        try:
            wn.add_pipe(
                _BURST_LINK,
                _BURST_NODE,
                anchor,
                length=1.0,
                diameter=0.1,
                roughness=100.0,
                initial_status="CLOSED",
            )
            try:
                write_inpfile(wn, path, units=units, version=2.2)
            finally:
                wn.remove_link(_BURST_LINK)
        finally:
            wn.remove_node(_BURST_NODE)
            hydraulic.demand_model, times.duration = saved

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        """Close the EPANET project and delete its scratch files (idempotent)."""
        if self._en is not None:
            self._lib.EN_close(self._ph)
            self._lib.EN_deleteproject(self._ph)
            self._en = None
        if self._tmp is not None:
            self._tmp.cleanup()
            self._tmp = None

    # --- toolkit helpers -----------------------------------------------------------------------
    def _check(self, code: int, what: str) -> None:
        if code > 100:  # below 100: EPANET's warnings (negative pressures, ...), not failures
            buf = ctypes.create_string_buffer(256)
            self._lib.EN_geterror(code, buf, 255)
            raise SimulationError(
                f"EPANET error {code} {what}: {buf.value.decode(errors='replace')}"
            )

    def _indices(self, nodes: Sequence[str]) -> list[int]:
        """Toolkit indices of ``nodes`` (kept: nodes are never added or deleted once open)."""
        key = tuple(nodes)
        if key not in self._index_cache:
            self._index_cache = {key: [self._node_index(n) for n in nodes]}
        return self._index_cache[key]

    def _node_index(self, name: str) -> int:
        return self._index("EN_getnodeindex", "node", name)

    def _link_index(self, name: str) -> int:
        return self._index("EN_getlinkindex", "link", name)

    def _index(self, function: str, kind: str, name: str) -> int:
        """The toolkit index of the node or link ``name`` (``function``: the toolkit's lookup)."""
        index = ctypes.c_int()
        code = getattr(self._lib, function)(self._ph, name.encode(), ctypes.byref(index))
        if code:
            raise NetworkError(f"unknown {kind} {name!r}")
        return index.value

    def _node_value(self, index: int, prop: int) -> float:
        value = ctypes.c_double()
        self._check(
            self._lib.EN_getnodevalue(self._ph, index, prop, ctypes.byref(value)), "reading a node"
        )
        return value.value

    def _link_value(self, index: int, prop: int) -> float:
        value = ctypes.c_double()
        self._check(
            self._lib.EN_getlinkvalue(self._ph, index, prop, ctypes.byref(value)), "reading a link"
        )
        return value.value

    def _solve(self, nodes: Sequence[int]) -> NDArray[np.float64]:
        """EPANET's first time step from scratch; heads (m) at ``nodes`` (toolkit indices)."""
        lib, ph = self._lib, self._ph
        self._check(lib.EN_openH(ph), "opening the hydraulic solver")
        try:
            self._check(lib.EN_initH(ph, _EN_INITFLOW), "initialising the hydraulics")
            t = ctypes.c_long()
            self._check(lib.EN_runH(ph, ctypes.byref(t)), "solving the steady state")
            value, get, byref = ctypes.c_double(), lib.EN_getnodevalue, ctypes.byref
            heads = []
            for i in nodes:  # the hot loop: one toolkit call per node, errors checked after
                if get(ph, i, _EN_HEAD, byref(value)):
                    self._check(get(ph, i, _EN_HEAD, byref(value)), "reading a head")
                heads.append(value.value)
        finally:
            lib.EN_closeH(ph)
        return np.asarray(
            self._to_si(self._units, np.asarray(heads), self._param.HydraulicHead),
            dtype=np.float64,
        )

    # --- the public part -----------------------------------------------------------------------
    def heads(self, nodes: Sequence[str]) -> NDArray[np.float64]:
        """Steady heads (m) at ``nodes`` of the unmodified network."""
        return self._solve(self._indices(nodes))

    def split_heads(
        self, pipe: str, fraction: float, emitter: float, nodes: Sequence[str]
    ) -> NDArray[np.float64]:
        """Steady heads (m) at ``nodes`` with ``pipe`` split at ``fraction`` of its length (from
        its INP start node) by a junction with an emitter of coefficient ``emitter`` (SI,
        m³/s per m^0.5). The project is restored afterwards.

        Raises:
            NetworkError: ``pipe`` is not a pipe.
            ConfigError: ``fraction`` not strictly between 0 and 1.
        """
        if not 0.0 < fraction < 1.0:
            raise ConfigError(f"position must be strictly between 0 and 1, got {fraction!r}")
        wn = self._wn
        link = wn.get_link(pipe) if pipe in self._pipes else None
        if link is None:
            raise NetworkError(f"unknown pipe {pipe!r}")
        indices = self._indices(nodes)
        lib, ph = self._lib, self._ph
        li = self._link_index(pipe)
        start, end = link.start_node, link.end_node
        elevation = split_elevation(link, fraction)
        length = self._link_value(li, _EN_LENGTH)
        props = [self._link_value(li, p) for p in (_EN_DIAMETER, _EN_ROUGHNESS, _EN_MINORLOSS)]
        status = self._link_value(li, _EN_INITSTATUS)
        n1, n2 = self._node_index(start.name), self._node_index(end.name)
        burst, spare = self._node_index(_BURST_NODE), self._link_index(_BURST_LINK)
        c = ctypes.c_double
        elev = float(self._from_si(self._units, elevation, self._param.Elevation))
        coeff = float(self._from_si(self._units, emitter, self._param.EmitterCoeff))
        kind = _EN_CVPIPE if link.check_valve else _EN_PIPE
        try:
            self._check(lib.EN_setnodevalue(ph, burst, _EN_ELEVATION, c(elev)), "burst junction")
            self._check(lib.EN_setnodevalue(ph, burst, _EN_EMITTER, c(coeff)), "burst emitter")
            self._check(lib.EN_setlinknodes(ph, li, n1, burst), "moving the pipe's end")
            self._check(lib.EN_setlinknodes(ph, spare, burst, n2), "laying the second part")
            if kind == _EN_CVPIPE:  # a pipe and a check valve swap type in place
                self._check(
                    lib.EN_setlinktype(ph, ctypes.byref(ctypes.c_int(spare)), kind, 0), "CV"
                )
            self._check(
                lib.EN_setpipedata(ph, spare, c(length * (1.0 - fraction)), *map(c, props)),
                "setting the second part",
            )
            if kind == _EN_PIPE:  # a check valve's status is EPANET's to decide
                self._check(lib.EN_setlinkvalue(ph, spare, _EN_INITSTATUS, c(status)), "status")
            self._check(lib.EN_setlinkvalue(ph, li, _EN_LENGTH, c(length * fraction)), "length")
            return self._solve(indices)
        finally:  # the pipe back as it was, the spare part closed and the burst junction off
            lib.EN_setlinknodes(ph, li, n1, n2)
            lib.EN_setlinkvalue(ph, li, _EN_LENGTH, c(length))
            if kind == _EN_CVPIPE:
                lib.EN_setlinktype(ph, ctypes.byref(ctypes.c_int(spare)), _EN_PIPE, 0)
            lib.EN_setlinkvalue(ph, spare, _EN_INITSTATUS, c(0.0))
            lib.EN_setnodevalue(ph, burst, _EN_EMITTER, c(0.0))


def split_elevation(link: Any, fraction: float) -> float:
    """The elevation (m) of the junction splitting the pipe ``link`` (a WNTR pipe) at
    ``fraction`` of its length from its INP start node: interpolated between its ends, a
    reservoir end taking the other end's elevation (a reservoir's is its head)."""
    start, end = link.start_node, link.end_node
    if start.node_type == "Reservoir":
        return float(end.elevation)
    if end.node_type == "Reservoir":
        return float(start.elevation)
    return float(start.elevation + (end.elevation - start.elevation) * fraction)
