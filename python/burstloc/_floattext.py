"""Exact decimal text of many floats at once, made by NumPy: lines of text without a Python
loop over the values, so that writing a large file leaves the GIL to the other threads.

:func:`float_text` gives each finite value a decimal text that ``float()`` reads back to the
same value, bit for bit (``-0.0`` keeps its sign). A value with at most 15 significant digits
(a reading as a meter sends it, ``52.3417``) gets the fewest decimals that read back to it: the
text of ``repr`` for ``1e-4 <= |v| < 1e16``, positional below. The text ``D``
with ``s`` decimals is checked by computing ``D / 10**s`` in floating point: with ``D < 2**53``
and ``s <= 22`` both are exact, so the division is rounded correctly, as ``float()`` of the text
is. Any other value in ``[1e-6, 1e16)`` gets 17 significant digits (always enough to read back)
of its exact product with a power of ten (Dekker's two-product), trailing zeros dropped; the
rare values beyond (smaller than ``1e-6`` or from ``1e16`` on, with more digits) get ``repr``.
Every step is a NumPy operation on whole arrays, which releases the GIL while it runs.

The texts come as rows of ASCII bytes right-aligned in a matrix, with their lengths;
:func:`joined` puts several such fields side by side, row by row, as one ``bytes``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

__all__ = ["Texts", "float_text", "joined", "text_rows"]

Texts = tuple[npt.NDArray[np.uint8], npt.NDArray[np.int64]]
"""Texts as rows of bytes right-aligned in an ``(n, width)`` matrix, and each one's length."""

_EXACT = 2.0**53  # integers up to here are exact in a float64
_TENS = 10.0 ** np.arange(23)  # exact in a float64
_TENS_INT = 10 ** np.arange(19, dtype=np.int64)  # every power of ten an int64 holds
_SPLIT = 134_217_729.0  # 2**27 + 1: Veltkamp's split of a float64 into two halves
_SHORT = 23  # decimals tried for the shortest text (while 10**s is exact and D < 2**53)
_DIGITS = 17  # significant digits that always read back
_LOW, _HIGH = 1e-6, 1e16  # the range of the 17-digit texts (their powers of ten exact)
_ZERO, _POINT, _MINUS = ord("0"), ord("."), ord("-")


Floats = npt.NDArray[np.float64]
Ints = npt.NDArray[np.int64]


def _two_product(a: Floats, b: Floats) -> tuple[Floats, Floats]:
    """``(p, e)`` with ``p = fl(a * b)`` and ``p + e == a * b`` exactly (Dekker)."""
    p = a * b
    c = _SPLIT * a
    a_hi = c - (c - a)
    a_lo = a - a_hi
    c = _SPLIT * b
    b_hi = c - (c - b)
    b_lo = b - b_hi
    return p, ((a_hi * b_hi - p) + a_hi * b_lo + a_lo * b_hi) + a_lo * b_lo


def _shortest(a: Floats, digits: Ints, decimals: Ints) -> npt.NDArray[np.intp]:
    """Fill ``digits`` and ``decimals`` where ``|v| = a`` has at most 15 significant digits
    (module docstring); the indices of the others."""
    pending = np.arange(a.shape[0])
    left = a
    for s in range(_SHORT):
        scaled = left * _TENS[s]
        whole = np.rint(scaled)
        ok = (whole <= _EXACT) & (whole / _TENS[s] == left)
        found = pending[ok]
        digits[found] = whole[ok]
        decimals[found] = s
        pending, left = pending[~ok], left[~ok]
        if not pending.size or bool((scaled[~ok] > _EXACT).all()):
            break  # more decimals would only be larger
    return pending


def _seventeen(a: Floats) -> tuple[Ints, Ints, npt.NDArray[np.bool_]]:
    """17 significant digits of each ``a`` (``digits``, ``decimals``) and where they hold."""
    inside = (a >= _LOW) & (a < _HIGH)
    safe = np.where(inside, a, 1.0)
    decimals = (_DIGITS - 1 - np.floor(np.log10(safe))).astype(np.int64)
    p, e = _two_product(safe, _TENS[np.clip(decimals, 0, 22)])
    short = p < 10.0 ** (_DIGITS - 1)  # log10 may be one too high next to a power of ten
    if short.any():
        decimals += short
        p, e = _two_product(safe, _TENS[np.clip(decimals, 0, 22)])
    inside &= decimals <= 22
    # p >= 1e16 > 2**53 is a whole number: the nearest integer to p + e is p + rint(e)
    digits = p.astype(np.int64) + np.rint(e).astype(np.int64)
    while True:  # trailing zeros dropped, one decimal kept
        zero = (decimals > 1) & (digits % 10 == 0)
        if not zero.any():
            return digits, decimals, inside
        digits[zero] //= 10
        decimals[zero] -= 1


def float_text(values: npt.ArrayLike) -> Texts:
    """The text of each of ``values`` (1-D, finite) that reads back to it (module docstring).

    Raises:
        ValueError: a value that is not finite, or ``values`` not one-dimensional.
    """
    v = np.asarray(values, dtype=np.float64)
    if v.ndim != 1:
        raise ValueError(f"float_text takes a 1-D array, got {v.ndim} dimensions")
    if not np.isfinite(v).all():
        raise ValueError("float_text takes finite values only (a NaN or an infinity was given)")
    n = v.shape[0]
    if n == 0:
        return np.zeros((0, 1), np.uint8), np.zeros(0, np.int64)
    a = np.abs(v)
    digits = np.zeros(n, np.int64)
    decimals = np.zeros(n, np.int64)
    other: list[bytes] = []
    with np.errstate(all="ignore"):  # huge values overflow where they are not used
        rest = _shortest(a, digits, decimals)
        if rest.size:
            longer, places, inside = _seventeen(a[rest])
            digits[rest[inside]], decimals[rest[inside]] = longer[inside], places[inside]
            rest = rest[~inside]
            other = [repr(float(v[i])).encode("ascii") for i in rest]
    whole = decimals == 0  # "50.0", as repr writes it
    digits[whole] *= 10
    decimals[whole] = 1
    negative = np.signbit(v)
    count = np.ones(n, np.int64)  # each one's digits
    for j in range(1, 19):
        more = digits >= _TENS_INT[j]
        if not more.any():
            break
        count += more
    places = np.maximum(count, decimals + 1)  # "0.05": a zero before the point
    lengths = negative + places + 1
    width = int(max(lengths.max(), max(map(len, other), default=1)))
    shown = int(places.max())
    table = np.zeros((shown + 1, n), np.uint8)  # row j: the digit of 10**j (zeros past the last)
    left = digits
    for j in range(min(shown, 19)):
        left, table[j] = np.divmod(left, 10)
    table += _ZERO
    point = decimals.astype(np.int8)
    minus = np.where(negative, lengths - 1, -1).astype(np.int8)
    out = np.empty((n, width), np.uint8)
    for r in range(width):  # the column r places from the right
        below = table[min(r, shown)]  # a digit right of the point
        above = table[min(r - 1, shown)] if r else below  # left of it
        column = np.where(point > r, below, np.where(point == r, np.uint8(_POINT), above))
        column[minus == r] = _MINUS
        out[:, width - 1 - r] = column
    for i, text in zip(rest.tolist(), other, strict=True):
        out[i, width - len(text) :] = np.frombuffer(text, np.uint8)
        lengths[i] = len(text)
    return out, lengths


def text_rows(texts: Sequence[bytes]) -> Texts:
    """``texts`` as :data:`Texts`."""
    lengths = np.array([len(t) for t in texts], dtype=np.int64)
    out = np.zeros((len(texts), int(lengths.max(initial=0))), np.uint8)
    for row, text in zip(out, texts, strict=True):
        if text:
            row[-len(text) :] = np.frombuffer(text, np.uint8)
    return out, lengths


def joined(fields: Sequence[Texts]) -> bytes:
    """Each row's texts of ``fields`` side by side, the rows one after another."""
    matrix = np.concatenate([m for m, _ in fields], axis=1)
    shown = np.concatenate(
        [np.arange(m.shape[1] - 1, -1, -1)[None, :] < n[:, None] for m, n in fields], axis=1
    )
    return matrix[shown].tobytes()
