"""golden.codebook.bounds: Elkan's half gaps are lower bounds of the true ones (float32 screening
lowered by its error bound), and tight enough to be of use."""
import numpy as np
import pytest

from vqtex.golden.codebook import bounds
from vqtex.golden.codebook.screen import Screen


def _exact_half_gaps(c):
    d2 = ((c[:, None, :] - c[None, :, :]) ** 2).sum(-1)
    np.fill_diagonal(d2, np.inf)
    return 0.5 * np.sqrt(d2.min(1))


def _codebook(rng, k, d, near):
    c = rng.integers(0, 256, (k, d)).astype(np.float64)
    # near ties: pairs of codewords one or two units apart in one component
    c[1: 2 * near: 2] = c[0: 2 * near: 2]
    c[1: 2 * near: 2, 0] += rng.integers(1, 3, near)
    return c


@pytest.mark.parametrize("d,k", [(12, 256), (48, 1024)])
def test_half_gaps_full_and_moved_are_lower_bounds(d, k):
    rng = np.random.default_rng(d)
    c = _codebook(rng, k, d, near=40)
    scr = Screen(rng.integers(0, 256, (500, d)).astype(np.float64), np.full(d, 127.5))
    exact = _exact_half_gaps(c)
    full = bounds._half_gaps(c, scr)
    assert np.all(full <= exact)
    # tight: lowered by the float32 error bound only (squared distances, rmax^2 ~ 2e5..8e5)
    slack = 1e-4 * ((c - 127.5) ** 2).sum(1).max()
    assert np.all((2 * full) ** 2 >= (2 * exact) ** 2 - slack)
    # a few codewords move (some onto near ties): only their rows are screened again
    moved = np.sort(rng.choice(k, k // 8, replace=False))
    c2 = c.copy()
    c2[moved] += rng.normal(0, 3, (moved.size, d))
    c2[moved[:10]] = c2[(moved[:10] + 1) % k] + 0.5
    exact2 = _exact_half_gaps(c2)
    part = bounds._half_gaps(c2, scr, moved, exact)
    assert np.all(part <= exact2)
    slack = 1e-4 * ((c2 - 127.5) ** 2).sum(1).max()
    assert np.all((2 * part) ** 2 >= (2 * np.minimum(exact, exact2)) ** 2 - slack)


def test_half_gaps_one_moved_codeword_has_no_nan():
    """One moved codeword: its own column has no other moved row (+inf, never NaN)."""
    rng = np.random.default_rng(5)
    c = _codebook(rng, 64, 12, near=4)
    scr = Screen(c, np.full(12, 127.5))
    exact = _exact_half_gaps(c)
    c2 = c.copy()
    c2[7] += 4.0
    with np.errstate(invalid="raise"):
        part = bounds._half_gaps(c2, scr, np.array([7]), exact)
    assert not np.isnan(part).any() and np.all(part <= _exact_half_gaps(c2))
