"""burstloc.live.history: the monitor's recent rows in one ring array."""

from __future__ import annotations

from collections import deque

import numpy as np
import pytest

from burstloc.exceptions import InputError
from burstloc.live.history import RowHistory


@pytest.mark.parametrize("capacity", [1, 2, 7])
def test_the_rows_kept_are_a_bounded_deque_s(capacity: int) -> None:
    rng = np.random.default_rng(capacity)
    history, reference = RowHistory(capacity, 3), deque(maxlen=capacity)
    for k in range(4 * capacity + 3):
        row = rng.normal(size=3)
        history.append(row)
        reference.append(row.copy())
        assert len(history) == len(reference)
        assert np.array_equal(history.array(), np.array(reference).reshape(-1, 3))
        for count in range(capacity + 2):
            expected = np.array(list(reference)[max(len(reference) - count, 0) :])
            assert np.array_equal(history.last(count), expected.reshape(-1, 3)), (k, count)
    assert history.tolist() == np.array(reference).tolist()


def test_a_row_is_copied_in_whatever_its_layout() -> None:
    history = RowHistory(4, 3)
    matrix = np.asfortranarray(np.arange(12.0).reshape(3, 4))
    column = matrix[:, 1]  # not contiguous in memory
    whole = np.array([7, 8, 9])  # integers
    row = np.array([1.5, 2.5, 3.5])
    for r in (column, whole, row):
        history.append(r)
    row[:] = -1.0  # the caller's array written afterwards: the history keeps what it was given
    matrix[:] = -1.0
    assert history.array().tolist() == [[1.0, 5.0, 9.0], [7.0, 8.0, 9.0], [1.5, 2.5, 3.5]]
    out = history.last(2)
    out[:] = 0.0  # a row read out is the caller's own
    assert history.last(2).tolist() == [[7.0, 8.0, 9.0], [1.5, 2.5, 3.5]]


def test_a_saved_history_comes_back_and_bad_rows_are_refused() -> None:
    history = RowHistory(3, 2)
    history.extend([[1.0, 2.0], [3.0, 4.0], [5.0, 6.0], [7.0, 8.0]])
    again = RowHistory(3, 2)
    again.extend(history.tolist())
    assert again.tolist() == [[3.0, 4.0], [5.0, 6.0], [7.0, 8.0]] == history.tolist()
    with pytest.raises(InputError, match="a row of 2 values expected"):
        history.append(np.ones(3))
    with pytest.raises(InputError, match="at least one row"):
        RowHistory(0, 2)
    assert history.tolist() == again.tolist()
