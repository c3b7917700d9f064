"""Missile geometry as data: the body profile, the eight fins and the rigid-body properties.

All coordinates are in the missile body frame B of :mod:`flexnet_fe.frames`: origin at the nose
apex, ``+x_b`` forward along the axis, the missile occupies ``x_b ∈ [-L, 0]``; a fin's roll angle
φ is measured from ``+y_b`` towards ``+z_b``. The station is ``s = -x_b`` (distance aft of apex)
and the radial distance from the axis is ``r``; ``(s, r)`` is the meridian half-plane in which
the body of revolution is described by its profile.

Fin frame (one per fin): origin at the root leading edge on the body surface,
``e1`` = outward radial direction (span), ``e2 = -x̂_b`` (chord, leading to trailing edge),
``n = e1 × e2`` (plate normal, points towards increasing roll angle). In-plane coordinates
``(u, v) = ((p - o)·e1, (p - o)·e2)``; the trapezoid corners, counter-clockwise in (u, v), are
``root TE (0, c_r)``, ``root LE (0, 0)``, ``tip LE (b, b tanΛ)``, ``tip TE (b, b tanΛ + c_t)``, so
edge k joins corner k to corner k+1: 0 root, 1 leading edge, 2 tip, 3 trailing edge
(:data:`EDGE_NAMES`, the names of the mesh physical groups).

The paper models the missile in LS-DYNA (§V-C: body SOLID164, wings and rudders SHELL163) from
a CAD model of Fig. 10 whose dimensions (Table 1) are lost; see :mod:`flexnet_fe.missile.config`
for the defaults used instead and their sources.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from flexnet_fe.missile.config import FinMaterial, FinSetConfig, MissileConfig, NoseShape
from flexnet_fe.missile.planform import trapezoid

EDGE_NAMES: tuple[str, str, str, str] = ("root", "leading_edge", "tip", "trailing_edge")
"""Fin edge k joins corner k to corner k+1 (mod 4); these are also the mesh physical groups."""


class FinKind(str, Enum):
    WING = "wing"
    RUDDER = "rudder"


class PrimKind(int, Enum):
    """Kind of a body-profile primitive in the meridian half-plane (s, r)."""

    SEGMENT = 0
    ARC = 1


@dataclass(frozen=True)
class ProfilePrimitive:
    """One piece of the body profile in the meridian half-plane (s [m], r [m]).

    SEGMENT: ``data = (s0, r0, s1, r1)``. ARC: ``data = (s_c, r_c, rho, th0, th1)``, the circle of
    centre (s_c, r_c) and radius rho between polar angles th0 < th1 [rad] (angle measured in the
    (s, r) plane from +s towards +r). ``part``: 0 body (cylinder, base), 1 nose.
    """

    kind: PrimKind
    data: tuple[float, ...]
    part: int


@dataclass(frozen=True)
class Fin:
    """A flat trapezoidal fin plate of its real thickness (geometry in B, SI units).

    corners [m], shape (4, 3): root TE, root LE, tip LE, tip TE (mid-plane, B frame).
    uv [m], shape (4, 2): the same corners in fin-plane coordinates (u along e1, v along e2).
    origin [m], shape (3,): root leading edge. e1, e2, n: unit vectors, shape (3,).
    """

    name: str
    kind: FinKind
    index: int
    roll_angle: float  # [rad]
    root_chord: float  # [m]
    tip_chord: float  # [m]
    span: float  # [m]
    leading_edge_sweep: float  # [rad]
    thickness: float  # [m]
    origin: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    n: np.ndarray
    corners: np.ndarray
    uv: np.ndarray
    material: FinMaterial
    tip_corner_radius: float = 0.0  # [m] planform radius of the tip corners (contact shape only)

    @property
    def area(self) -> float:
        """Planform area of the trapezoid [m^2]: (c_r + c_t) b / 2."""
        return 0.5 * (self.root_chord + self.tip_chord) * self.span

    def to_plane(self, p: np.ndarray) -> np.ndarray:
        """Fin-frame coordinates (u, v, w) [m], shape (n, 3), of points p [m], shape (n, 3) in B."""
        d = np.atleast_2d(p) - self.origin
        return np.stack([d @ self.e1, d @ self.e2, d @ self.n], axis=-1)

    def edge_length(self, k: int) -> float:
        """Length of edge k (see :data:`EDGE_NAMES`) [m]."""
        return float(np.linalg.norm(self.uv[(k + 1) % 4] - self.uv[k]))


@dataclass(frozen=True)
class Missile:
    """The rigid missile (body frame B): shape, fins and rigid-body properties.

    length L [m], radius R [m], nose_length L_n [m]; profile: the closed body profile in the
    meridian half-plane from the apex (s=0, r=0) to the base centre (s=L, r=0);
    mass [kg]; cg [m], shape (3,), in B; inertia [kg m^2], shape (3, 3), about the CG in B axes;
    fins: wing_1..wing_4 then rudder_1..rudder_4.
    """

    name: str
    length: float
    radius: float
    nose_shape: NoseShape
    nose_length: float
    profile: tuple[ProfilePrimitive, ...]
    fins: tuple[Fin, ...]
    mass: float
    cg: np.ndarray
    inertia: np.ndarray

    def fin(self, name: str) -> Fin:
        """The fin called ``name`` (KeyError if there is none)."""
        for f in self.fins:
            if f.name == name:
                return f
        raise KeyError(f"no fin named {name!r}; fins are {[f.name for f in self.fins]}")


def _frozen(a) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a


def body_profile(length: float, radius: float, nose_shape: NoseShape,
                 nose_length: float) -> tuple[ProfilePrimitive, ...]:
    """The closed profile of the body of revolution in the meridian half-plane (s, r) [m].

    Nose from the apex (0, 0) to (L_n, R): cone = straight segment; tangent ogive = circular arc of
    radius ρ = (R² + L_n²)/(2R) centred at (L_n, R - ρ), tangent to the cylinder at s = L_n;
    hemisphere = the tangent ogive with L_n = R (ρ = R, centre (R, 0)). Then the cylinder
    (L_n, R)–(L, R) and the flat base (L, R)–(L, 0).
    """
    L, R, Ln = float(length), float(radius), float(nose_length)
    if nose_shape is NoseShape.CONE:
        nose = ProfilePrimitive(PrimKind.SEGMENT, (0.0, 0.0, Ln, R), 1)
    elif nose_shape in (NoseShape.TANGENT_OGIVE, NoseShape.HEMISPHERE):
        rho = (R * R + Ln * Ln) / (2.0 * R)
        sc, rc = Ln, R - rho
        th0 = np.pi / 2.0  # the tangent point (L_n, R) is straight "above" the centre
        th1 = float(np.arctan2(-rc, -sc) % (2.0 * np.pi))  # the apex (0, 0), ≈ in (pi/2, pi]
        nose = ProfilePrimitive(PrimKind.ARC, (sc, rc, rho, th0, th1), 1)
    else:  # an Enum member added without geometry
        raise ValueError(f"unknown nose shape {nose_shape!r}")
    cyl = ProfilePrimitive(PrimKind.SEGMENT, (Ln, R, L, R), 0)
    base = ProfilePrimitive(PrimKind.SEGMENT, (L, R, L, 0.0), 0)
    return (nose, cyl, base)


def nose_radius(s: np.ndarray, radius: float, nose_shape: NoseShape,
                nose_length: float) -> np.ndarray:
    """Nose radius r(s) [m] at stations s ∈ [0, L_n] [m] (same shapes as :func:`body_profile`)."""
    s = np.asarray(s, dtype=np.float64)
    R, Ln = float(radius), float(nose_length)
    if nose_shape is NoseShape.CONE:
        return R * s / Ln
    # arc: r = sqrt(ρ² - (L_n - s)²) - (ρ - R); with ρ² - L_n² = (ρ - R)² (from the definition of
    # ρ) this is r = s (2 L_n - s) / (sqrt((ρ - R)² + s (2 L_n - s)) + ρ - R): no cancellation at
    # the apex (ρ - R = (L_n² - R²)/(2R) >= 0 for L_n >= R)
    a = (Ln * Ln - R * R) / (2.0 * R)
    g = s * (2.0 * Ln - s)
    den = np.sqrt(a * a + g) + a
    # den = 0 only at a hemisphere's apex (a = 0, s = 0), where r = 0
    return np.divide(g, den, out=np.zeros_like(g), where=den > 0.0)


def build_fin(name: str, kind: FinKind, index: int, fs: FinSetConfig, roll_deg: float,
              body_radius: float, material: FinMaterial) -> Fin:
    """One fin plate from its fin-set parameters and roll angle (see the module docstring)."""
    phi = np.deg2rad(roll_deg)
    lam = np.deg2rad(fs.leading_edge_sweep_deg)
    e1 = np.array([0.0, np.cos(phi), np.sin(phi)])
    e1[np.abs(e1) < 1e-15] = 0.0  # cos 90° = 6e-17: fins at multiples of 90° exactly in a plane
    e2 = np.array([-1.0, 0.0, 0.0])
    n = np.cross(e1, e2)
    origin = np.array([-fs.root_le_station, 0.0, 0.0]) + body_radius * e1
    uv = trapezoid(fs.span, fs.root_chord, fs.tip_chord, fs.leading_edge_sweep_deg)
    corners = origin + uv[:, :1] * e1 + uv[:, 1:] * e2
    return Fin(name=name, kind=kind, index=index, roll_angle=float(phi),
               root_chord=fs.root_chord, tip_chord=fs.tip_chord, span=fs.span,
               leading_edge_sweep=float(lam), thickness=fs.thickness,
               origin=_frozen(origin), e1=_frozen(e1), e2=_frozen(e2), n=_frozen(n),
               corners=_frozen(corners), uv=_frozen(uv), material=material,
               tip_corner_radius=fs.tip_corner_radius)


def build_fins(cfg: MissileConfig) -> tuple[Fin, ...]:
    """wing_1..wing_4 then rudder_1..rudder_4 (this order = part ids 2..9 of the contact shapes)."""
    R = 0.5 * cfg.body_diameter
    fins = []
    for kind, fs in ((FinKind.WING, cfg.wings), (FinKind.RUDDER, cfg.rudders)):
        for i, roll in enumerate(fs.roll_angles_deg):
            fins.append(build_fin(f"{kind.value}_{i + 1}", kind, len(fins), fs, roll, R,
                                  cfg.material))
    return tuple(fins)
