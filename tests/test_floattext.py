"""burstloc._floattext: every finite float's text reads back to it bit for bit (hypothesis, over
the whole range and next to the powers of ten where the paths change); a value of at most 15
significant digits (a reading as a meter sends it) gets the text ``repr`` gives it; texts side
by side make the lines expected; what is not a finite 1-D array is refused by name."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from burstloc._floattext import float_text, joined, text_rows


def _texts(values: list[float]) -> list[str]:
    matrix, lengths = float_text(np.array(values, dtype=np.float64))
    width = matrix.shape[1]
    return [bytes(row[width - n :]).decode("ascii") for row, n in zip(matrix, lengths, strict=True)]


def _bits(x: float) -> bytes:
    return struct.pack("<d", x)


def _read_back(values: list[float]) -> None:
    for value, text in zip(values, _texts(values), strict=True):
        assert _bits(float(text)) == _bits(value), (value, text)


@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=1, max_size=60))
def test_every_finite_float_reads_back_bit_for_bit(values: list[float]) -> None:
    _read_back(values)


@given(
    st.lists(
        st.floats(min_value=1e-7, max_value=1e17, allow_nan=False, allow_infinity=False),
        min_size=1,
        max_size=60,
    )
)
def test_the_17_digit_range_reads_back(values: list[float]) -> None:
    _read_back(values + [-v for v in values])


def test_the_edges_of_each_path_read_back() -> None:
    tens = [10.0**k for k in range(-9, 19)]
    edges = [0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308, 1.7976931348623157e308]
    edges += [2.0**53, 2.0**53 + 2, 2.0**53 - 1, 0.1 + 0.2, 1.0 + 2**-52, 1e-6 * 0.999]
    edges += tens + [float(np.nextafter(t, 0.0)) for t in tens]
    edges += [float(np.nextafter(t, np.inf)) for t in tens]
    edges += [2.0**k for k in range(-40, 70)]
    _read_back(edges + [-x for x in edges])


@given(
    st.lists(
        st.tuples(st.integers(-(10**15) + 1, 10**15 - 1), st.integers(0, 20)),
        min_size=1,
        max_size=60,
    )
)
def test_a_value_of_15_digits_gets_the_text_repr_gives_it(parts: list[tuple[int, int]]) -> None:
    values = [n / 10**d for n, d in parts]  # at most 15 significant digits, as meters send them
    values = [v for v in values if v == 0 or 1e-4 <= abs(v) < 1e16] or [0.0]
    assert _texts(values) == [repr(v) for v in values]


def test_an_empty_array_has_no_text() -> None:
    matrix, lengths = float_text(np.zeros(0))
    assert matrix.shape[0] == 0 and lengths.shape == (0,)


def test_texts_side_by_side_make_the_lines() -> None:
    stamps = float_text([12.5, 12.75, -3.0])
    names = text_rows([b",N2,", b",", b",meter-long,"])
    values = float_text([181.2, 0.05, 1e-9])
    newline = text_rows([b"\n"] * 3)
    assert joined([stamps, names, values, newline]) == (
        b"12.5,N2,181.2\n12.75,0.05\n-3.0,meter-long,0.000000001\n"
    )


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ([1.0, float("nan")], "finite values only"),
        ([float("inf")], "finite values only"),
        ([[1.0, 2.0]], "1-D array, got 2 dimensions"),
    ],
)
def test_what_is_not_a_finite_1d_array_is_refused_by_name(
    values: list[object], message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        float_text(values)  # type: ignore[arg-type]
