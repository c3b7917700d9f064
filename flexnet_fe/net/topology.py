"""Net models (what never changes during a deployment) and their builders.

Frame: world frame W of ``flexnet_fe.frames`` — the net lies flat in the x–y plane at t = 0,
centred on the origin, flight along +z, +y up. Each rope segment is one tension-only
spring-damper between two lumped masses (paper §III-A, Eq. (1)–(4)); each node carries half
the mass of every segment it ends (plus any concentrated mass: corner, tip, hub).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from flexnet_fe.net.config import RotaryNet, TractionNet, WarpInitialState
from flexnet_fe.net.forces import RopeMaterial, rope_material
from flexnet_fe.net.kernels import spring_blocks


@dataclass(frozen=True)
class NetModel:
    """A lumped-mass rope net. n nodes, m segments (springs).

    Attributes
    ----------
    kind : "traction" or "rotary".
    x0 : initial positions [m], shape (n, 3).
    v0 : initial velocities relative to the launching interceptor [m/s], shape (n, 3);
         the deploy stage adds the uniform flight velocity.
    mass : lumped node masses [kg], shape (n,).
    springs : node pairs (i, j) of each segment, shape (m, 2), int64.
    rest_length : unstretched segment lengths l0 [m], shape (m,).
    stiffness_ea : axial rigidity E·A [N], shape (m,); K = EA / l0, Eq. (3).
    damping : dashpot coefficients c [N s/m], shape (m,); Eq. (4), see :func:`segment_damping`.
    slack_offset : LINK167 offset [m], shape (m,); the segment is taut when its length exceeds
         ``rest_length - slack_offset`` (> 0 pretension, < 0 slack).
    diameter : rope diameter d [m], shape (m,) (aerodynamic size, Eq. (5)–(6)).
    drag_free : shape (n,), bool; True where the node carries a concentrated body (corner mass,
         tip mass, hub) whose own aerodynamic load is not modelled (the paper has no law for it).
         Rope-segment loads still act on these nodes.
    mass_nodes : indices of the corner (traction) or tip (rotary) masses, shape (k,), int64.
    cells : triangles covering the net surface, shape (c, 3), int64 (area definition).
    boundary_loop : ordered nodes of the outer perimeter, shape (b,), int64.
    hub_node : index of the hub's centre node (rotary) or -1.
    hub_link : shape (m,), bool; True for the segments that join a warp to the hub rim.
         For those, ``springs[s, 0] == hub_node`` and the rope starts on the rim at
         ``anchor_angle[s]`` (hub frame, from +x at θ = 0), Eq. (12)–(19).
    anchor_angle : [rad], shape (m,); 0 where not a hub link.
    hub_radius : r0 [m]; hub_length : axial length H [m]; hub_inertia : J [kg m^2];
    hub_spin0 : initial ω about +z [rad/s].
    rope : the rope's material (E, ν, ρ, d, transverse modulus, strength), its one home; the
         builders derive stiffness_ea, diameter and the lumped rope mass from it (None only for
         hand-built test models).
    """

    kind: str
    x0: np.ndarray
    v0: np.ndarray
    mass: np.ndarray
    springs: np.ndarray
    rest_length: np.ndarray
    stiffness_ea: np.ndarray
    damping: np.ndarray
    slack_offset: np.ndarray
    diameter: np.ndarray
    drag_free: np.ndarray
    mass_nodes: np.ndarray
    cells: np.ndarray
    boundary_loop: np.ndarray
    hub_node: int = -1
    hub_link: np.ndarray | None = None
    anchor_angle: np.ndarray | None = None
    hub_radius: float = 0.0
    hub_length: float = 0.0
    hub_inertia: float = 0.0
    hub_spin0: float = 0.0
    rope: RopeMaterial | None = None

    def __post_init__(self):
        m = len(self.springs)
        if self.hub_link is None:
            object.__setattr__(self, "hub_link", np.zeros(m, dtype=np.bool_))
        if self.anchor_angle is None:
            object.__setattr__(self, "anchor_angle", np.zeros(m))
        for name in ("x0", "v0", "mass", "springs", "rest_length", "stiffness_ea", "damping",
                     "slack_offset", "diameter", "drag_free", "mass_nodes", "cells",
                     "boundary_loop", "hub_link", "anchor_angle"):
            getattr(self, name).setflags(write=False)

    @property
    def n_nodes(self) -> int:
        return len(self.mass)

    @property
    def n_springs(self) -> int:
        return len(self.springs)

    @cached_property
    def stiffness(self) -> np.ndarray:
        """Segment stiffness K = EA / l0 [N/m], shape (m,), Eq. (3) (computed once, read-only)."""
        return _frozen(segment_stiffness(self.stiffness_ea, self.rest_length))

    @cached_property
    def kernel_springs(self) -> np.ndarray:
        """``springs`` as uint32 (m, 2), the deploy kernel's index type (computed once, read-only)."""
        return _frozen(self.springs.astype(np.uint32))

    @cached_property
    def kernel_blocks(self) -> np.ndarray:
        """The segments in runs and per-segment blocks, (b, 6) int64, for the deploy kernel
        (``net.kernels.spring_blocks``; computed once, read-only)."""
        return _frozen(spring_blocks(self.springs, self.hub_link))

    @cached_property
    def links(self) -> np.ndarray:
        """Indices of the hub links, shape (k,), int64 (computed once, read-only)."""
        return _frozen(np.flatnonzero(self.hub_link))


def _frozen(a: np.ndarray) -> np.ndarray:
    """``a`` made read-only (the model's derived arrays are shared by every caller)."""
    a.setflags(write=False)
    return a


def segment_stiffness(ea: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """Axial stiffness K = EA / l0 [N/m] of segments of rigidity EA [N] and rest length l0 [m],
    Eq. (3) — the one place it is computed (``NetModel.stiffness``)."""
    return ea / rest


def segment_damping(stiffness: np.ndarray, m_i: np.ndarray, m_j: np.ndarray, zeta: float) -> np.ndarray:
    """Dashpot coefficient c = 2 ζ √(μ K) [N s/m], Eq. (4), shape like ``stiffness``.

    Departure from the paper: Eq. (4) writes the segment mass m_ij; we use the reduced mass
    μ = m_i m_j / (m_i + m_j) of the two end nodes, so that ζ is exactly the damping ratio of
    the segment's own axial mode (a two-mass oscillator) — the verification test checks this.
    """
    mu = m_i * m_j / (m_i + m_j)
    return 2.0 * zeta * np.sqrt(mu * stiffness)


def _lump(n: int, springs: np.ndarray, seg_mass: np.ndarray) -> np.ndarray:
    mass = np.zeros(n)
    np.add.at(mass, springs[:, 0], 0.5 * seg_mass)
    np.add.at(mass, springs[:, 1], 0.5 * seg_mass)
    return mass


class _Nodes:
    """Node coordinates being built: the knots first, then the interior nodes of each bar
    split into ``k`` segments (appended in the order the bars are added)."""

    def __init__(self, knots: np.ndarray, k: int):
        self.pts = [knots]
        self.next = len(knots)
        self.k = k

    def chain(self, p_a, p_b, a: int, b: int) -> list[int]:
        """Node ids of a bar from point p_a (node a) to point p_b (node b), k segments."""
        ids = [a]
        if self.k > 1:
            s_ = np.arange(1, self.k)[:, None] / self.k
            self.pts.append(p_a + s_ * (p_b - p_a))
            ids += list(range(self.next, self.next + self.k - 1))
            self.next += self.k - 1
        return ids + [b]

    def coordinates(self) -> np.ndarray:
        return np.vstack(self.pts)


def _rope_segments(cfg: TractionNet | RotaryNet, springs: np.ndarray, rest: np.ndarray, mass: np.ndarray) -> dict:
    """Rope law arrays of NetModel (stiffness_ea, damping, slack_offset, diameter), each (m,),
    and its ``rope`` material, from the ``[net]`` rope fields; ``mass`` (n,) [kg] the node masses incl. concentrated ones.
    ζ is the damping ratio of a whole mesh bar (k = 1). A bar split into k segments: with
    ``damping_law = "segment"`` every segment gets Eq. (4) from its own stiffness and end masses
    (the paper's per-segment law); with ``"material"`` the rope keeps the viscosity of the bar
    (dashpots in series: c_segment = k c_bar), so refinement converges to a viscous continuum."""
    k = cfg.subdivisions
    rope = rope_material(cfg)
    ea = np.full(len(springs), rope.youngs_modulus * rope_area(rope.diameter))
    factor = k if rope.damping_law == "material" else 1
    damping = factor * segment_damping(segment_stiffness(ea, rest), mass[springs[:, 0]], mass[springs[:, 1]],
                                       rope.damping_ratio)
    return dict(stiffness_ea=ea, damping=damping, slack_offset=np.full(len(springs), cfg.slack_offset / k),
                diameter=np.full(len(springs), rope.diameter), rope=rope)


def rope_area(diameter: float) -> float:
    """Rope cross-section A = π d² / 4 [m²] of diameter d [m]."""
    return 0.25 * np.pi * diameter**2


def _fan(ring: list[int]) -> list[tuple[int, int, int]]:
    """Triangles fanning a polygon of node ids from its first node."""
    return [(ring[0], ring[q], ring[q + 1]) for q in range(1, len(ring) - 1)]


def _traction_bars(nk: int, kid: list, nodes: _Nodes, knots: np.ndarray):
    """Springs (list of pairs) and the node chain of every mesh bar keyed by its knot pair;
    ``kid`` the knot ids as nested lists (Python ints: fast dict keys)."""
    springs, bar_nodes = [], {}

    def add_bar(a, b):
        chain = nodes.chain(knots[a], knots[b], a, b)
        springs.extend(zip(chain[:-1], chain[1:]))
        bar_nodes[(a, b)] = chain

    for i in range(nk):
        for j in range(nk - 1):
            add_bar(kid[i][j], kid[i][j + 1])
    for i in range(nk - 1):
        for j in range(nk):
            add_bar(kid[i][j], kid[i + 1][j])
    return springs, bar_nodes


def _traction_cells_and_loop(nk: int, kid: list, bar_nodes: dict):
    """Cells (each mesh square the polygon of its subdivided edges, fanned from a corner) and
    the ordered perimeter nodes."""
    tris = []
    for i in range(nk - 1):
        for j in range(nk - 1):
            ring = (bar_nodes[(kid[i][j], kid[i][j + 1])][:-1]
                    + bar_nodes[(kid[i][j + 1], kid[i + 1][j + 1])][:-1]
                    + bar_nodes[(kid[i + 1][j], kid[i + 1][j + 1])][::-1][:-1]
                    + bar_nodes[(kid[i][j], kid[i + 1][j])][::-1][:-1])
            tris.extend(_fan(ring))
    loop = (sum((bar_nodes[(kid[0][j], kid[0][j + 1])][:-1] for j in range(nk - 1)), [])
            + sum((bar_nodes[(kid[i][-1], kid[i + 1][-1])][:-1] for i in range(nk - 1)), [])
            + sum((bar_nodes[(kid[-1][j], kid[-1][j + 1])][::-1][:-1] for j in reversed(range(nk - 1))), [])
            + sum((bar_nodes[(kid[i][0], kid[i + 1][0])][::-1][:-1] for i in reversed(range(nk - 1))), []))
    return np.asarray(tris, dtype=np.int64), np.asarray(loop, dtype=np.int64)


def _traction_springs_unsplit(kid: np.ndarray) -> np.ndarray:
    """:func:`_traction_bars`' springs (m, 2) for unsplit bars (k = 1), in its order: the bars
    along a row (i, j)–(i, j+1) row by row, then (i, j)–(i+1, j); ``kid`` (nk, nk) knot ids."""
    along = np.column_stack([kid[:, :-1].ravel(), kid[:, 1:].ravel()])
    across = np.column_stack([kid[:-1, :].ravel(), kid[1:, :].ravel()])
    return np.vstack([along, across]).astype(np.int64)


def _traction_cells_and_loop_unsplit(kid: np.ndarray):
    """:func:`_traction_cells_and_loop` for unsplit bars (k = 1): each square (a, b, c, d) =
    (i, j), (i, j+1), (i+1, j+1), (i+1, j) fanned from a into (a, b, c), (a, c, d); the
    perimeter from knot (0, 0) along row 0, down the last column, back along the last row and
    up column 0."""
    a, b, c, d = kid[:-1, :-1], kid[:-1, 1:], kid[1:, 1:], kid[1:, :-1]
    tris = np.stack([np.stack([a, b, c], axis=-1), np.stack([a, c, d], axis=-1)], axis=2).reshape(-1, 3)
    loop = np.concatenate([kid[0, :-1], kid[:-1, -1], kid[-1, :0:-1], kid[:0:-1, 0]])
    return tris.astype(np.int64), loop.astype(np.int64)


def build_traction(cfg: TractionNet) -> NetModel:
    """Square traction net (paper §V-A): N × N knots, N = edge/mesh + 1, each mesh bar split
    into ``cfg.subdivisions`` segments; four corner masses launched outwards.

    Launch velocity of the corner at (sx, sy) = (±1, ±1):
    V (cos e · (sx cos a, sy sin a), sin e) with a = ``launch_azimuth_deg`` from the x edge,
    e = ``launch_elevation_deg`` towards +z.
    """
    nk = int(round(cfg.edge_length / cfg.mesh_size)) + 1
    if abs((nk - 1) * cfg.mesh_size - cfg.edge_length) > 1e-9 * cfg.edge_length:
        raise ValueError(f"edge_length {cfg.edge_length} m is not a multiple of mesh_size {cfg.mesh_size} m")
    coords = -0.5 * cfg.edge_length + cfg.mesh_size * np.arange(nk)
    X, Y = np.meshgrid(coords, coords)  # knot (row i = y index, col j = x index)
    knots = np.column_stack([X.ravel(), Y.ravel(), np.zeros(nk * nk)])
    kid = np.arange(nk * nk).reshape(nk, nk)
    if cfg.subdivisions == 1:  # no split: the same arrays, vectorised (0.3 s of Python at 101 × 101 knots)
        x0, springs = knots, _traction_springs_unsplit(kid)
    else:
        nodes = _Nodes(knots, cfg.subdivisions)
        springs, bar_nodes = _traction_bars(nk, kid.tolist(), nodes, knots)
        x0 = nodes.coordinates()
        springs = np.asarray(springs, dtype=np.int64)
    n = len(x0)

    rest = np.linalg.norm(x0[springs[:, 1]] - x0[springs[:, 0]], axis=1)
    mass = _lump(n, springs, cfg.density * rope_area(cfg.rope_diameter) * rest)
    corners = np.array([kid[0, 0], kid[0, -1], kid[-1, -1], kid[-1, 0]], dtype=np.int64)
    mass[corners] += cfg.corner_mass

    v0 = np.zeros((n, 3))
    a, e = np.radians(cfg.launch_azimuth_deg), np.radians(cfg.launch_elevation_deg)
    for c in corners:
        sx, sy = np.sign(x0[c, 0]), np.sign(x0[c, 1])
        v0[c] = cfg.corner_speed * np.array([np.cos(e) * sx * np.cos(a), np.cos(e) * sy * np.sin(a), np.sin(e)])
    if cfg.subdivisions == 1:
        cells, loop = _traction_cells_and_loop_unsplit(kid)
    else:
        cells, loop = _traction_cells_and_loop(nk, kid.tolist(), bar_nodes)
    drag_free = np.zeros(n, dtype=np.bool_)
    drag_free[corners] = True
    return NetModel(kind="traction", x0=x0, v0=v0, mass=mass, springs=springs, rest_length=rest,
                    drag_free=drag_free, mass_nodes=corners, cells=cells, boundary_loop=loop,
                    **_rope_segments(cfg, springs, rest, mass))


def _rotary_bars(cfg: RotaryNet, nodes: _Nodes, knots: np.ndarray, nid: np.ndarray, ang: np.ndarray):
    """Springs, hub-link flags, anchor angles (lists, one per segment) and the node chains of
    the warp bars (key (w, i); (w, -1) the rim bar) and weft bars (key (w, i))."""
    nw, M, r0 = cfg.warps, nid.shape[1], cfg.hub_radius
    springs, hub_link, anchor = [], [], []
    warp_bars, weft_bars = {}, {}

    def add(ids, first_is_link=False, a_w=0.0):
        for q, (i, j) in enumerate(zip(ids[:-1], ids[1:])):
            link = first_is_link and q == 0
            springs.append((i, j)); hub_link.append(link); anchor.append(a_w if link else 0.0)

    for w in range(nw):
        rim = r0 * np.array([np.cos(ang[w]), np.sin(ang[w]), 0.0])
        warp_bars[(w, -1)] = ids = nodes.chain(rim, knots[nid[w, 0]], 0, nid[w, 0])
        add(ids, True, ang[w])
        for i in range(M - 1):
            warp_bars[(w, i)] = ids = nodes.chain(knots[nid[w, i]], knots[nid[w, i + 1]], nid[w, i], nid[w, i + 1])
            add(ids)
    for w in range(nw):
        u = (w + 1) % nw
        for i in range(M):
            weft_bars[(w, i)] = ids = nodes.chain(knots[nid[w, i]], knots[nid[u, i]], nid[w, i], nid[u, i])
            add(ids)
    return (np.asarray(springs, dtype=np.int64), np.asarray(hub_link, dtype=np.bool_), np.asarray(anchor),
            warp_bars, weft_bars)


def _rotary_cells_and_loop(nw: int, M: int, warp_bars: dict, weft_bars: dict):
    """Cells (the hub sector and each mesh quadrilateral, fanned) and the perimeter nodes."""
    tris = []
    for w in range(nw):
        u = (w + 1) % nw
        tris.extend(_fan(warp_bars[(w, -1)][:-1] + weft_bars[(w, 0)][:-1] + warp_bars[(u, -1)][::-1][:-1]))
        for i in range(M - 1):
            tris.extend(_fan(warp_bars[(w, i)][:-1] + weft_bars[(w, i + 1)][:-1]
                             + warp_bars[(u, i)][::-1][:-1] + weft_bars[(w, i)][::-1][:-1]))
    loop = sum((weft_bars[(w, M - 1)][:-1] for w in range(nw)), [])
    return np.asarray(tris, dtype=np.int64), np.asarray(loop, dtype=np.int64)


def _rotary_velocities(cfg: RotaryNet, x0: np.ndarray, tips: np.ndarray, ang: np.ndarray) -> np.ndarray:
    """Initial velocities (n, 3) [m/s]: warps at rest or in rigid rotation, hub at rest, tips
    launched tangentially at ``tip_speed``."""
    v0 = np.zeros((len(x0), 3))
    if cfg.warp_initial_state is WarpInitialState.RIGID_ROTATION:
        v0[:, 0] = -cfg.hub_spin * x0[:, 1]
        v0[:, 1] = cfg.hub_spin * x0[:, 0]
    elif cfg.warp_initial_state is not WarpInitialState.REST:
        raise ValueError(f"unknown warp_initial_state {cfg.warp_initial_state!r}")
    v0[0] = 0.0
    v0[tips, 0] = -cfg.tip_speed * np.sin(ang)
    v0[tips, 1] = cfg.tip_speed * np.cos(ang)
    return v0


def build_rotary(cfg: RotaryNet) -> NetModel:
    """Rotary net (paper §III-B, §V-A): hub node 0 at the origin; warp w has knots at radii
    r0 + i h (i = 1..M, M = warp_length / h) along angle 2π w / n; wefts join knot i of
    adjacent warps (straight chords, initially unstretched); tip mass at i = M. Each bar (radial
    or weft) is split into ``cfg.subdivisions`` segments.

    The segment from the rim to the first node of each warp is a *hub link*: it starts on the
    rim (anchor angle 2π w / n) and may wind onto the hub (Eq. (17)–(19), ``flexnet_fe.net.hub``).
    """
    nw, h, r0, k = cfg.warps, cfg.mesh_size, cfg.hub_radius, cfg.subdivisions
    M = int(round(cfg.warp_length / h))
    if abs(M * h - cfg.warp_length) > 1e-9 * cfg.warp_length:
        raise ValueError(f"warp_length {cfg.warp_length} m is not a multiple of mesh_size {h} m")
    ang = 2 * np.pi * np.arange(nw) / nw
    r = r0 + h * np.arange(1, M + 1)
    nid = 1 + np.arange(nw)[:, None] * M + np.arange(M)[None, :]  # knot (warp, ring)
    knots = np.zeros((1 + nw * M, 3))
    knots[nid, 0] = r[None, :] * np.cos(ang)[:, None]
    knots[nid, 1] = r[None, :] * np.sin(ang)[:, None]
    nodes = _Nodes(knots, k)
    springs, hub_link, anchor, warp_bars, weft_bars = _rotary_bars(cfg, nodes, knots, nid, ang)
    x0 = nodes.coordinates()
    n = len(x0)

    # rest length: hub links run from the rim to their first node; others node to node
    rest = np.linalg.norm(x0[springs[:, 1]] - x0[springs[:, 0]], axis=1)
    rest[hub_link] = h / k
    mass = _lump(n, springs, cfg.density * rope_area(cfg.rope_diameter) * rest)
    mass[0] += cfg.hub_mass
    tips = nid[:, -1].astype(np.int64)
    mass[tips] += cfg.tip_mass
    cells, loop = _rotary_cells_and_loop(nw, M, warp_bars, weft_bars)
    drag_free = np.zeros(n, dtype=np.bool_)
    drag_free[tips] = True
    drag_free[0] = True
    J = cfg.hub_inertia if cfg.hub_inertia is not None else 0.5 * cfg.hub_mass * r0**2
    return NetModel(
        kind="rotary", x0=x0, v0=_rotary_velocities(cfg, x0, tips, ang), mass=mass, springs=springs,
        rest_length=rest, drag_free=drag_free, mass_nodes=tips, cells=cells, boundary_loop=loop, hub_node=0,
        hub_link=hub_link, anchor_angle=anchor, hub_radius=r0, hub_length=cfg.hub_length, hub_inertia=J,
        hub_spin0=cfg.hub_spin, **_rope_segments(cfg, springs, rest, mass))


def build_net(net: TractionNet | RotaryNet) -> NetModel:
    """The NetModel of a ``[net]`` section."""
    if isinstance(net, TractionNet):
        return build_traction(net)
    if isinstance(net, RotaryNet):
        return build_rotary(net)
    raise TypeError(f"unknown net section {type(net).__name__}")
