"""The monitor's recent readings: the last rows of every meter's values, in one ring array.

:class:`RowHistory` keeps the last ``capacity`` time steps (one float64 row of ``width`` values
each) in a single ``(capacity, width)`` array. A row goes in by a plain memory copy
(:class:`memoryview` slice assignment, done holding the GIL) and the rows come out as one 2-D
array by at most two NumPy copies. A deque of row arrays stacked by ``np.array(rows)`` at every
look did the same work with one NumPy copy per row, and NumPy 1.x lets go of the GIL around
every copy however small: a thread beside the monitor that waits for the GIL (the incident
store's writer) then wakes at each of those hand-overs, rarely gets it, and costs the loop
about a tenth of its CPU time while it waits (``benches/bench_incidents.py``, section 3).
Numpy only: on the live path.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
from numpy.typing import NDArray

from burstloc.exceptions import InputError

__all__ = ["RowHistory"]


class RowHistory:
    """The last ``capacity`` rows of ``width`` float64 values, oldest first (module docstring).

    Examples
    --------
    >>> h = RowHistory(3, 2)
    >>> for k in range(4):
    ...     h.append(np.array([k, 10.0 * k]))
    >>> len(h), h.last(2).tolist()
    (3, [[2.0, 20.0], [3.0, 30.0]])
    >>> h.array()[:, 1].tolist()
    [10.0, 20.0, 30.0]
    """

    def __init__(self, capacity: int, width: int) -> None:
        if capacity < 1 or width < 1:
            raise InputError(
                f"a history needs at least one row and one column, got {capacity} x {width}"
            )
        self.capacity = int(capacity)
        self.width = int(width)
        self._rows = np.zeros((self.capacity, self.width), dtype=np.float64)
        self._flat = self._rows.reshape(-1).data  # the same memory: 1-D, format "d"
        self._next = 0  # the slot the next row goes to
        self._count = 0

    def __len__(self) -> int:
        return self._count

    def append(self, row: NDArray[np.float64]) -> None:
        """Keep a copy of ``row`` (``width`` values) as the newest row.

        Raises:
            InputError: ``row`` does not hold ``width`` values.
        """
        if row.shape != (self.width,):
            raise InputError(f"a row of {self.width} values expected, got shape {row.shape}")
        at = self._next * self.width
        if row.dtype == np.float64 and row.flags.c_contiguous:
            self._flat[at : at + self.width] = row.data  # memcpy, the GIL held
        else:
            self._rows[self._next] = row
        self._next = (self._next + 1) % self.capacity
        self._count = min(self._count + 1, self.capacity)

    def last(self, count: int) -> NDArray[np.float64]:
        """The newest ``count`` rows (at most those kept), oldest first, as a new array."""
        count = max(0, min(int(count), self._count))
        start = (self._next - count) % self.capacity
        if count == 0:
            return np.empty((0, self.width), dtype=np.float64)
        if start + count <= self.capacity:
            return self._rows[start : start + count].copy()
        head = self.capacity - start
        out = np.empty((count, self.width), dtype=np.float64)
        out[:head] = self._rows[start:]
        out[head:] = self._rows[: count - head]
        return out

    def array(self) -> NDArray[np.float64]:
        """Every row kept, oldest first, as a new ``(len(self), width)`` array."""
        return self.last(self._count)

    def extend(self, rows: Iterable[Iterable[float]]) -> None:
        """Append each of ``rows`` in turn (e.g. a saved state's)."""
        for row in rows:
            self.append(np.asarray(row, dtype=np.float64))

    def tolist(self) -> list[list[float]]:
        """Every row kept, oldest first, as lists of floats (JSON-ready)."""
        return self.array().tolist()
