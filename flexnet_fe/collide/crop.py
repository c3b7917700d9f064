"""Crop: integrate only the part of the net the impact can reach; hold the rest.

Within the simulated time T a disturbance travels along a rope at most at the wave speed; for
the linear rope law the longitudinal speed in material coordinates is c = sqrt(E/ρ) (31.6 m/s
for the paper's 1 MPa, 1000 kg/m³ rope: 0.38 m in 12 ms), and a transverse (kink) wave under a
strain ε runs at c·sqrt(ε), faster than c once ε > 1 — which the 1 MPa rope reaches. The
reach is therefore ``factor × c × T + margin`` beyond the missile's swept footprint (its bounding
radius around the flight path), with ``factor`` (default 4, i.e. strains up to 16) a case
parameter. Nodes within the reach of the path line are free, the others are held at rest.
``boundary_motion`` measures how far the free nodes next to the held ones moved, so a crop that
was too small shows up; the tests compare cropped and full nets on the paper's cases.
"""

from __future__ import annotations

import numpy as np


def wave_speed(youngs_modulus: float, density: float) -> float:
    """Longitudinal rope wave speed sqrt(E/ρ) [m/s] (E [Pa], ρ [kg/m³])."""
    return float(np.sqrt(youngs_modulus / density))


def crop_reach(footprint_radius: float, wave_speed_mps: float, duration: float, factor: float,
               margin: float) -> float:
    """Distance from the flight path [m] within which net nodes are integrated."""
    return footprint_radius + factor * wave_speed_mps * duration + margin


def free_nodes(x: np.ndarray, aim: np.ndarray, direction: np.ndarray, reach: float) -> np.ndarray:
    """Nodes whose distance from the line through ``aim`` [m] (3,) along unit ``direction`` (3,)
    is at most ``reach`` [m]. x [m] (n, 3). Returns (n,) bool."""
    rel = x - aim
    along = rel @ direction
    perp = np.linalg.norm(rel - np.outer(along, direction), axis=1)
    return perp <= reach


def active_segments(springs: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Indices of the segments with at least one free end, (k,) int64."""
    return np.flatnonzero(free[springs[:, 0]] | free[springs[:, 1]])


def boundary_nodes(springs: np.ndarray, free: np.ndarray) -> np.ndarray:
    """Free nodes joined by a segment to a held node, (k,) int64 (empty when nothing is held)."""
    a, b = springs[:, 0], springs[:, 1]
    mixed = free[a] != free[b]
    ends = np.concatenate([a[mixed], b[mixed]])
    return np.unique(ends[free[ends]])


def boundary_motion(x0: np.ndarray, x: np.ndarray, boundary: np.ndarray) -> float:
    """Largest displacement [m] of the crop's boundary nodes (0 when there are none)."""
    if boundary.size == 0:
        return 0.0
    return float(np.max(np.linalg.norm(x[boundary] - x0[boundary], axis=1)))
