"""The set operations by sorting give NumPy's arrays."""

from __future__ import annotations

import numpy as np
import pytest

from vemwear.util.arrays import isin, unique


@pytest.mark.parametrize("n", [0, 1, 2, 17, 10_000])
def test_unique_and_isin_are_numpys(n: int) -> None:
    rng = np.random.default_rng(n)
    a = rng.integers(-50, 50, size=(n, 3)) if n else np.zeros((0, 3), dtype=np.int64)
    u = unique(a)
    assert u.dtype == np.unique(a).dtype
    np.testing.assert_array_equal(u, np.unique(a))
    for values in (rng.integers(-60, 60, size=7), np.zeros(0, dtype=np.int64), a[:5]):
        got = isin(a, values)
        assert got.shape == a.shape
        np.testing.assert_array_equal(got, np.isin(a, values))
    x = rng.random(n)
    np.testing.assert_array_equal(unique(np.concatenate([x, x])), np.unique(x))
