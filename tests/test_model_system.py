"""The initial state's checks (``model.system``): the values they compare are bit for bit
those of the elementwise forms they stand for."""
from __future__ import annotations

import numpy as np


def test_the_initial_checks_extremes_are_the_elementwise_ones():
    """``_check_resolved`` and ``check_admissible`` take the largest spacing error and the
    smallest strain from the extreme differences: bit for bit what the elementwise forms
    give, since a subtraction and x -> x n - 1 are monotone in floating point."""
    rng = np.random.default_rng(7)
    for n in (1, 2, 5, 40, 1000):
        for scale in (1e-12, 1e-3, 1.0, 1e8):
            u = np.cumsum(rng.uniform(0.5, 1.5, n + 1)) * scale / n + rng.normal() * scale
            d = u[1:] - u[:-1]
            spacing = float(np.median(d))
            assert max(d.max() - spacing, spacing - d.min()) == np.abs(d - spacing).max()
            assert d.min() * n - 1.0 == (d * n - 1.0).min()
