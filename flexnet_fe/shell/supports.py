"""Edge supports of the shell (no dolfinx import: the case schema uses them)."""

from __future__ import annotations

from enum import Enum


class Support(str, Enum):
    """Edge support of the shell (a named choice; an unknown name is an error)."""

    CLAMPED = "clamped"
    """u and θ fixed (the fin root on the missile body)"""
    SIMPLY_SUPPORTED = "simply_supported"
    """w = u·n = 0 only: in-plane motion and rotations free (soft simple support)"""
    SIMPLY_SUPPORTED_HARD = "simply_supported_hard"
    """w = 0 and the fibre's tilt along the edge θ·s = 0 (Navier's support); the edge must run
    along e1 or e2 of the fin basis; in-plane motion free"""
    PINNED = "pinned"
    """u fixed (all three components), θ free"""
    FREE = "free"
    """nothing fixed"""


_SUPPORT_COMPONENTS = {Support.CLAMPED: (0, 1, 2, 3, 4), Support.PINNED: (0, 1, 2),
                       Support.SIMPLY_SUPPORTED: (), Support.SIMPLY_SUPPORTED_HARD: (),
                       Support.FREE: ()}
NORMAL_FIXED = (Support.SIMPLY_SUPPORTED, Support.SIMPLY_SUPPORTED_HARD)
"""supports that constrain w = u·n (a projection, since n need not be a frame axis)"""
