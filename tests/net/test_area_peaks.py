"""``net.deploy.area_peaks`` (the area maxima with prominence >= 5 % of the range, written out
without scipy.signal) against its reference ``scipy.signal.find_peaks(area,
prominence=0.05 * range)``: the same indices on random, plateau-rich and deployment-like
histories."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import find_peaks

from flexnet_fe.net.deploy import area_peaks


def _reference(a):
    rng = float(a.max() - a.min())
    return np.zeros(0, dtype=int) if rng <= 0 else find_peaks(a, prominence=0.05 * rng)[0]


@pytest.mark.parametrize("seed", range(40))
def test_area_peaks_equals_scipy_find_peaks(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 120))
    a = rng.random(n)
    if seed % 3 == 0:  # plateaus and ties
        a = np.round(a * 5) / 5
    if seed % 4 == 1:  # an opening/closing net: damped oscillation plus noise
        t = np.linspace(0, 0.4, n)
        a = 25 + 70 * np.abs(np.sin(12 * t)) * np.exp(-2 * t) + 0.5 * rng.random(n)
    np.testing.assert_array_equal(area_peaks(a), _reference(a))


def test_area_peaks_flat_and_tiny():
    for a in (np.ones(5), np.array([1.0]), np.array([1.0, 2.0]), np.array([0.0, 1.0, 1.0, 0.0])):
        np.testing.assert_array_equal(area_peaks(a), _reference(a))
