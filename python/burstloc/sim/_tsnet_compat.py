"""TSNet 0.3.1 on numpy 2 and WNTR >= 1.4: four small patches, applied before every run.

TSNet 0.3.1 (its last release) was written against numpy 1 and WNTR 1.3. Three of its
functions leave 1-element arrays where numbers belong, and numpy 2 refuses to convert them
to scalars; one relies on WNTR accepting a zero pipe roughness:

* ``tsnet.network.discretize.cal_N`` returns the reaches per pipe as an ``(n, 1)`` array, so
  ``int(Ndis[i])`` in ``discretization`` fails. Patched: the same numbers as a flat array.
* ``tsnet.network.discretize.adjust_wavev`` computes the time step and each pipe's adjusted
  wave speed through ``(1, 1)`` matrix products, so ``tm.time_step`` and every ``pipe.wavev``
  are 1-element arrays; ``'%.5f' % tm.time_step`` in ``set_time`` and the MOC solver's
  element assignments then fail. Patched: TSNet's own function runs unchanged, then these
  values are stored as the NumPy float64 scalars they hold (the same bits).
* ``tsnet.simulation.solver.add_leakage`` (every junction: demand, emitter, burst) returns the
  node's velocity as a 1-element array, which ``tsnet.simulation.single`` stores into an
  element of its velocity array; numpy 2 refuses. Patched (where ``single`` calls it): the
  same value as a float64 scalar.
* ``tsnet.simulation.initialize.cal_roughness_coef`` sets the roughness of a pipe without
  steady flow to 0 (no friction); WNTR >= 1.4 rejects a roughness <= 0. Patched: that case
  stores the 0 past WNTR's check, exactly as TSNet meant; every other case runs TSNet's code.

Nothing else changes: on the pinned stack (numpy 1.26, WNTR 1.3.2) the patched TSNet gives
bit-identical heads (``tests/sim/test_tsnet_compat.py`` checks this, and checks numpy 2 against
heads stored from the pinned stack). TSNet is MIT-licensed; the thresholds below are TSNet's.
"""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType
from typing import Any

import numpy as np

from burstloc.exceptions import SimulatorMissingError

__all__ = ["applied", "load"]

#: TSNet's thresholds in ``cal_roughness_coef``: below either, the pipe has no friction.
_V_TOL = 1e-5
_H_TOL = 1e-3

_ORIGINALS: dict[str, Callable[..., Any]] = {}


def applied() -> bool:
    """Whether :func:`load` has patched TSNet in this process."""
    return bool(_ORIGINALS)


def load() -> ModuleType:
    """Import TSNet, patched (once per process), and return it.

    Raises:
        SimulatorMissingError: TSNet is not installed (it comes with the ``sim`` extra).
    """
    try:
        import tsnet
        from tsnet.network import discretize
        from tsnet.simulation import initialize, single
    except ImportError as exc:
        raise SimulatorMissingError(exc) from exc
    if not _ORIGINALS:
        _ORIGINALS["cal_N"] = discretize.cal_N
        _ORIGINALS["adjust_wavev"] = discretize.adjust_wavev
        _ORIGINALS["cal_roughness_coef"] = initialize.cal_roughness_coef
        _ORIGINALS["add_leakage"] = single.add_leakage
        discretize.cal_N = _cal_n
        discretize.adjust_wavev = _adjust_wavev
        initialize.cal_roughness_coef = _cal_roughness_coef
        single.add_leakage = _add_leakage
    return tsnet


def _scalar(value: Any) -> np.float64:
    """A 1-element array (or a number) as the float64 scalar it holds."""
    return np.float64(np.asarray(value, dtype=np.float64).item())


def _cal_n(tm: Any, dt: float) -> np.ndarray:
    """TSNet's ``cal_N`` as a flat array (``int(N[i])`` needs a scalar under numpy 2)."""
    return np.asarray(_ORIGINALS["cal_N"](tm, dt)).ravel()


def _adjust_wavev(tm: Any) -> Any:
    """TSNet's ``adjust_wavev``, then its time step and wave speeds as float64 scalars."""
    tm = _ORIGINALS["adjust_wavev"](tm)
    tm.time_step = _scalar(tm.time_step)
    for _, pipe in tm.pipes():
        pipe.wavev = _scalar(pipe.wavev)
    return tm


def _cal_roughness_coef(pipe: Any, velocity: Any, head_loss: Any) -> Any:
    """TSNet's ``cal_roughness_coef``; a pipe without steady flow gets roughness 0 past WNTR."""
    if abs(velocity) >= _V_TOL and head_loss >= _H_TOL:
        return _ORIGINALS["cal_roughness_coef"](pipe, velocity, head_loss)
    pipe._roughness = 0  # TSNet's "no friction"; WNTR >= 1.4's setter refuses 0
    pipe.roughness_height = 0
    return pipe


def _add_leakage(*args: Any, **kwargs: Any) -> tuple[Any, np.float64]:
    """TSNet's ``add_leakage``, its velocity (a 1-element array) as a float64 scalar."""
    head, velocity = _ORIGINALS["add_leakage"](*args, **kwargs)
    return head, _scalar(velocity)
