"""Where along its edge a rope strikes a fin: the strike envelope of ``shell.strike_envelope``
(issue 10).

Why: a rudder's peak stress in the paper cases follows one strike of the rope on its leading edge,
rope that rides on the body striking 1–10 mm above the clamped root. The peak depends steeply on
that height (radar × traction's rudder_2, the same loads moved along the edge: 186 / 269 / 287 /
327 / 325 / 328 / 269 MPa at 1.5 / 2.5 / 3.5 / 4.5 / 5.5 / 7.5 / 9.5 mm), and the model does not
fix the height to better than about a rope diameter: 0.97–1.7 mm at rope pieces of 1.4 mm (aim
point moved by 0.5–1 mm), 2.8–3.4 mm at 0.7 mm, 4.2 mm at 2.8 mm (docs/validation.md, "Where the
rope strikes"). A peak read at the one simulated height is one sample of that curve; the largest
peak over strike positions within a rope diameter of the simulated one is what a designer must
hold the fin to. It removes the height's share of the scatter (rudder_2 over seven such runs:
177–305 MPa, envelope 307–363), not the strike's strength (how much rope arrives together:
rudder_4 ±20 % either way): a single run's fin peaks stay undefined to ±8–20 %.

This module holds the geometry (pure functions): the fin's planform frame from its four corners
and the rigid move of a fin's load points along its leading edge, kept on the planform.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

STRIKE_OFFSETS = (-1.0, -0.5, 0.5, 1.0)
"""Moves of a fin's loads in span along its leading edge for the strike envelope, in rope
diameters (the contact width) [-]: the envelope is the largest peak over these and the run itself. A step
of half a diameter resolves the measured peak-against-height curve's plateau within ≈ 1 %
(rudder_2 above: 325–328 MPa over 4.5–7.5 mm)."""


class Planform(NamedTuple):
    """A trapezoidal fin in its plane: root leading-edge corner ``origin`` (3,) [m], chordwise unit
    ``u`` (3,) (along the root, towards the leading edge), spanwise unit ``s`` (3,) (in the plane,
    normal to the root, towards the tip), the span [m], and the leading and trailing edges' chordwise
    positions at root and tip [m] (u coordinates)."""

    origin: np.ndarray
    u: np.ndarray
    s: np.ndarray
    span: float
    le: tuple[float, float]
    te: tuple[float, float]


def planform(corners: np.ndarray) -> Planform:
    """The planform frame of a fin from its corners (4, 3) [m] in the order root TE, root LE,
    tip LE, tip TE (``missile.mesh.fin_outline_from_msh``); root and tip parallel."""
    root_te, root_le, tip_le, tip_te = np.asarray(corners, float)
    u = root_le - root_te
    u /= np.linalg.norm(u)
    d = tip_le - root_le
    s = d - (d @ u) * u
    span = float(np.linalg.norm(s))
    s /= span
    return Planform(root_le, u, s, span, (0.0, float(d @ u)), (float((root_te - root_le) @ u),
                                                               float((tip_te - root_le) @ u)))


def move_along_leading_edge(points: np.ndarray, pf: Planform, offset: float) -> np.ndarray:
    """``points`` (n, 3) [m] moved ``offset`` [m] in span (towards the tip; negative towards the
    root) along the leading edge's direction: a rigid move of the loads, so a point on the rounded
    leading edge (ahead of the planform's edge line, where the collision's capsule contact puts
    most of them) stays as far ahead of it, and the out-of-plane component is kept. Kept on the
    fin: a point within [0, span] stays within it (clipped at the root and tip lines; a point
    beyond one, on the rounded tip, moves only inwards), and a point at or ahead of the trailing
    edge stays so (the trailing edge is not parallel to the leading one). Returns a new array
    (n, 3). (In span, not along the edge: the uncertain quantity measured is the height above the
    root of a rope riding on the body.)"""
    p = np.asarray(points, float)
    r = p - pf.origin
    su, ss = r @ pf.u, r @ pf.s
    s_new = np.clip(ss + offset, np.minimum(ss, 0.0), np.maximum(ss, pf.span))
    u_new = su + (s_new - ss) * pf.le[1] / pf.span  # along the leading edge's direction

    def trailing(s):
        f = s / pf.span
        return pf.te[0] + f * (pf.te[1] - pf.te[0])

    u_new = np.where(su >= trailing(ss) - 1e-9, np.maximum(u_new, trailing(s_new)), u_new)  # (1 nm: on it)
    return p + np.outer(u_new - su, pf.u) + np.outer(s_new - ss, pf.s)
