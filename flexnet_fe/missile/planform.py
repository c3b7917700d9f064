"""Fin planform with rounded tip corners: pure functions on the trapezoid in fin-plane
coordinates (u along the span, v along the chord) [m].

A real fin's tip corners are rounded (millimetres to centimetres; the paper gives no planform
detail). For the rope contact the corner matters: a strand lying across a sharp corner is
resolved only by the fin's half-thickness h/2 (the contact shape is the core polygon swept by a
sphere of radius h/2), 1.5–2 mm, about two rope pieces of the collision's 0.7 mm, so whether the
strand sticks on the corner or slips off depends on where its nodes fall
(docs/collide_convergence.md, "Eq. (4) per segment, and the rudders' corner"). A corner radius R
replaces the corner by a circular arc tangent to both edges. The arc is stored as ARC_SEGMENTS
chords (inscribed), so the core stays a convex polygon and the exact segment–polygon distance of
``missile.shapes.segment_core_closest`` applies unchanged; the sphere sweep rounds each chord's
vertex by h/2 ≥ 1.5 mm, far more than the chords' sagitta R (1 − cos((π − θ) / (2 ARC_SEGMENTS)))
(θ the corner's interior angle; < 0.02 R for any corner, ≤ 0.005 R at the paper fins' tip corners,
θ ≈ 88–145°), so the contact normal turns continuously round the corner.
"""

from __future__ import annotations

import numpy as np

ARC_SEGMENTS = 8
"""Chords per rounded corner: a 90° corner turns 11.25° per chord (sagitta 0.48 % of R)."""

TIP_CORNERS = (2, 3)
"""Corner indices of the tip leading edge and tip trailing edge in the trapezoid (root TE, root LE,
tip LE, tip TE; ``missile.geometry``)."""


def trapezoid(span: float, root_chord: float, tip_chord: float, sweep_deg: float) -> np.ndarray:
    """The fin trapezoid (4, 2) [m]: root TE, root LE, tip LE, tip TE, counter-clockwise in (u, v)
    (``missile.geometry.build_fin`` builds every fin from it)."""
    v_le = span * np.tan(np.deg2rad(sweep_deg))
    return np.array([[0.0, root_chord], [0.0, 0.0], [span, v_le], [span, v_le + tip_chord]])


def _corner(poly: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Unit vectors from corner k along its incoming edge (to k − 1) and outgoing edge (to k + 1),
    and the interior angle θ [rad]."""
    c = poly[k]
    d1 = poly[k - 1] - c
    d2 = poly[(k + 1) % len(poly)] - c
    d1, d2 = d1 / np.linalg.norm(d1), d2 / np.linalg.norm(d2)
    return d1, d2, float(np.arccos(np.clip(d1 @ d2, -1.0, 1.0)))


def tip_corner_room(span: float, root_chord: float, tip_chord: float, sweep_deg: float) -> float:
    """Largest tip-corner radius [m] whose two arcs fit on the trapezoid's edges: the tangent
    lengths R / tan(θ/2) of the two tip corners share the tip edge, each also lies on its side
    edge (leading or trailing)."""
    poly = trapezoid(span, root_chord, tip_chord, sweep_deg)
    cot = [1.0 / np.tan(0.5 * _corner(poly, k)[2]) for k in TIP_CORNERS]
    edge = lambda k: float(np.linalg.norm(poly[(k + 1) % 4] - poly[k]))  # noqa: E731 (edge k: k → k + 1)
    return min(edge(2) / (cot[0] + cot[1]), edge(1) / cot[0], edge(3) / cot[1])


def round_tip_corners(poly: np.ndarray, radius: float, segments: int = ARC_SEGMENTS) -> np.ndarray:
    """The convex polygon ``poly`` (4, 2) [m] (counter-clockwise, corners as ``trapezoid``) with its
    two tip corners replaced by inscribed arcs of ``radius`` [m] (``segments`` chords each):
    (4 + 2 segments, 2). radius 0 returns ``poly``. The arc's centre lies on the corner's bisector
    at R / sin(θ/2); its ends are the tangent points at R / tan(θ/2) along each edge."""
    if radius <= 0.0:
        return np.array(poly, float)
    out = []
    for k in range(len(poly)):
        if k not in TIP_CORNERS:
            out.append(poly[k])
            continue
        d1, d2, theta = _corner(poly, k)
        bis = (d1 + d2) / np.linalg.norm(d1 + d2)
        centre = poly[k] + radius / np.sin(0.5 * theta) * bis
        t1 = poly[k] + radius / np.tan(0.5 * theta) * d1 - centre  # arc from the incoming edge
        phi0 = np.arctan2(t1[1], t1[0])
        turn = np.pi - theta  # counter-clockwise, as the polygon
        for j in range(segments + 1):
            phi = phi0 + turn * j / segments
            out.append(centre + radius * np.array([np.cos(phi), np.sin(phi)]))
    return np.array(out)
