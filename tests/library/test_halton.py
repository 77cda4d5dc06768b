"""The solvers' Halton points are scipy's, to the bit (``synth.numerics.halton`` replaces
``scipy.stats.qmc.Halton`` so that a synthesis does not import scipy.stats)."""

import numpy as np
import pytest
from scipy.stats import qmc

from synth.numerics.halton import halton


@pytest.mark.parametrize("d", range(1, 10))
def test_halton_is_scipys_unscrambled_sequence_to_the_bit(d):
    for n in (1, 2, 9, 321, 2561):  # up to 40 × 8 starts and beyond a power of each base
        assert np.array_equal(halton(d, n), qmc.Halton(d=d, scramble=False).random(n))
