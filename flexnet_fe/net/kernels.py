"""The compiled time-stepping kernel of the net (many steps per call, no Python per step).

Scheme: symplectic (semi-implicit) Euler, i.e. central differences with velocities at half
steps: v_{n+1/2} = v_{n-1/2} + dt f(x_n, v_{n-1/2}) / m ; x_{n+1} = x_n + dt v_{n+1/2}.
Second-order in positions for conservative forces; it conserves linear momentum and (for
central forces) angular momentum exactly. For a spring-dashpot with damping evaluated at the
lagged velocity the stability limit is ω dt <= 2 (√(1+ζ²) - ζ) (see ``timestep.py``).

Layout: inside a call the positions, velocities and forces are held as (3, n) arrays (one
contiguous row per component). A regular net's segments come in runs k0 … k0+L−1 joining nodes
(a0 + r, a0 + r + s): a row of horizontal bars (s = 1) or a layer of vertical ones (s = the row
length) (:func:`spring_blocks`). Over a run the end values are contiguous, so the rope law is
evaluated in SIMD registers without gathers (AVX-512 on this machine's EPYC), chunk by chunk into
an L1-sized scratch, and the forces are added to the nodes in conflict-free loops that give every
node its contributions in the order of the segment-by-segment loop: tensions, forces and
trajectories are the same to the bit (only the summed dissipation and air work are added in
another order). The other segments (hub links, short runs) take the per-segment loop.

A traction net's grid of W × H knots (its two blocks, no hub: :func:`_grid_shape`) takes its own
path, tile by tile of about TILE knots (whole knot rows): the law and the air of the tile's bars
in one vector loop each for the horizontal and the vertical ones (:func:`_grid_bars`, their data
laid out by knot once per call), then each knot's force, added in the per-segment loop's order,
and its update, while the tile is in cache (:func:`_grid_update`): no separate scatter, update or
air-work passes over the whole net. The same trajectories to the bit (tests/net/test_kernel_runs.py),
1.5–1.9× faster than the run path (docs/performance.md, issue 15).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from flexnet_fe.net.forces import C_CROSS, CD_FRICTION, segment_aero_force, spring_force
from flexnet_fe.net.hub import hub_link_state

C_MAX = CD_FRICTION + C_CROSS
CHUNK = 256
"""Segments of a run evaluated per pass (and about the knots of a grid tile, :func:`_grid_shape`):
the pass's scratch (12 rows of 256 floats in use) stays in L1."""
TILE = 2048
"""Knots per tile of a grid net (:func:`_grid_shape`), about."""
ROWLEN = TILE + CHUNK + 8
"""Entries per row of the scratch (13 ROWLEN,): a grid tile's (B + 1) W <= TILE + CHUNK; + 8,
one cache line, so that the rows do not start at multiples of 4 KiB (the same L1 sets)."""
MIN_RUN = 16
"""Shortest run taken by the vector path; shorter ones join the per-segment loop."""


def _merge_rows(runs: list) -> list:
    """Consecutive runs (k0, 1, length, a0, 0, s) of the same length and s whose first nodes
    step up by a constant stride merged into one block (k0, rows, length, a0, stride, s)."""
    out = []
    for k0, _, length, a0, _, s in runs:
        if out and out[-1][5] == s and out[-1][2] == length and out[-1][0] + out[-1][1] * length == k0:
            first_k0, rows, _, first_a0, stride, _ = out[-1]
            step = a0 - first_a0 if rows == 1 else stride
            if step > 0 and first_a0 + rows * step == a0:
                out[-1] = (first_k0, rows + 1, length, first_a0, step, s)
                continue
        out.append((k0, 1, length, a0, 0, s))
    return out


def spring_blocks(springs: np.ndarray, hub_link: np.ndarray, min_run: int = MIN_RUN) -> np.ndarray:
    """The segments split into blocks, in order, (b, 6) int64 rows (k0, rows, length, a0,
    stride, s). With s > 0 a run of rows: segment k0 + q length + r (q < rows, r < length) joins
    nodes a0 + q stride + r and that + s; length >= ``min_run``; no hub link (a traction net:
    all its horizontal bars one run of rows, s = 1, its vertical bars one row, s = row length).
    With s = 0 a block of rows × length segments of any kind (the per-segment loop; hub links
    in it are skipped there). ``springs`` (m, 2) node pairs, ``hub_link`` (m,) bool."""
    i = springs[:, 0].astype(np.int64)
    s = springs[:, 1].astype(np.int64) - i
    ok = ~np.asarray(hub_link, dtype=bool) & (s > 0)
    cont = np.zeros(len(i), dtype=bool)  # segment k continues the run of segment k - 1
    cont[1:] = ok[1:] & ok[:-1] & (i[1:] == i[:-1] + 1) & (s[1:] == s[:-1])
    starts = np.flatnonzero(~cont)
    counts = np.diff(np.append(starts, len(i)))
    blocks, runs, pending = [], [], -1  # pending: first segment of an open per-segment block
    for k0, count in zip(starts.tolist(), counts.tolist()):
        if ok[k0] and count >= min_run:
            if pending >= 0:
                blocks += _merge_rows(runs) + [(pending, 1, k0 - pending, 0, 0, 0)]
                runs, pending = [], -1
            runs.append((k0, 1, count, int(i[k0]), 0, int(s[k0])))
        elif pending < 0:
            pending = k0
    blocks += _merge_rows(runs)
    if pending >= 0:
        blocks.append((pending, 1, len(i) - pending, 0, 0, 0))
    return np.array(blocks, dtype=np.int64).reshape(-1, 6)


class DeployModel(NamedTuple):
    """What the deploy kernel needs and never changes (read-only in the kernel).

    springs (m, 2) uint32 node pairs (unsigned: no negative-index test in the hot loop); rest
    l0 [m], stiffness K = EA/l0 [N/m], damping c [N s/m],
    offset [m] (LINK167), diameter d [m], all (m,) — the rope law Eq. (1)–(4) and its aerodynamic
    size Eq. (5)–(6); hub_link (m,) bool; links (k,) int64 indices of the hub links; anchor (m,)
    [rad] rim angle of each hub link; mass (n,)
    [kg]; hub node index (-1: none); r0 hub radius [m]; half_length H/2 [m]; hub_inertia J
    [kg m²] (1 without a hub); gravity (3,) [m/s²]; rho air density [kg/m³]; wind (3,) [m/s];
    air: aerodynamic loads on/off; blocks (b, 6) int64 the segments in runs and per-segment
    blocks (:func:`spring_blocks`). Built by ``net.state.kernel_model``.
    """

    springs: np.ndarray
    rest: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    offset: np.ndarray
    diameter: np.ndarray
    hub_link: np.ndarray
    links: np.ndarray
    anchor: np.ndarray
    mass: np.ndarray
    hub: int
    r0: float
    half_length: float
    hub_inertia: float
    gravity: np.ndarray
    rho: float
    wind: np.ndarray
    air: bool
    blocks: np.ndarray


class DeployState(NamedTuple):
    """What the deploy kernel changes in place: x, v (n, 3) [m], [m/s]; hub (2,) = (θ [rad],
    ω [rad/s]); wrap (m,) wound angle of each hub link [rad]; tension (m,) [N] of the last force
    evaluation; losses (2,) [J], accumulated by :func:`advance`: (dissipated by the rope
    dashpots, work of the air on the motion about the centre of mass)."""

    x: np.ndarray
    v: np.ndarray
    hub: np.ndarray
    wrap: np.ndarray
    tension: np.ndarray
    losses: np.ndarray


@njit(cache=True, inline="always")
def _segment_air(model, v, s, ends, u, lf, vi, lam):
    """Rope aerodynamics of segment s, Eq. (5)–(10). Returns half its force [N] (3 floats), the
    share of each end (i, j) = ``ends`` (the hub's half acts on its translation only); adds the
    drag's velocity-derivative bound ½ ρ C_max d l |v_s| [kg/s] to lam[i], lam[j] (lam (n,)).
    u unit vector i → j, lf straight length [m] (> 0), vi velocity of end i [m/s] (3 floats)."""
    i, j = ends
    wind = model.wind
    vrel = (0.5 * (vi[0] + v[j, 0]) - wind[0], 0.5 * (vi[1] + v[j, 1]) - wind[1], 0.5 * (vi[2] + v[j, 2]) - wind[2])
    fx, fy, fz, vm = segment_aero_force(u, lf, vrel, model.rho, model.diameter[s])
    q = 0.5 * model.rho * C_MAX * model.diameter[s] * lf * vm
    lam[i] += q
    lam[j] += q
    return 0.5 * fx, 0.5 * fy, 0.5 * fz


@njit(cache=True, error_model="numpy")
def _block_forces(model, state, f, lam, fa, k0, k1):
    """Adds the tensions (Eq. 1–4) and, with air, the aerodynamics (Eq. 5–10) of segments
    k0 … k1−1 that are not hub links to f (n, 3) [N], the aerodynamics also to fa (n, 3) [N];
    writes their tension (m,) [N]. Returns (the largest tension [N], the dashpots' dissipation
    rate Σ (T − K s) l̇ [W] at the step's lagged velocities).

    The per-segment loop (gathers and scatters through the node indices): the segments that
    are not in a run (:func:`spring_blocks`)."""
    x = state.x
    v = state.v
    tension = state.tension
    springs = model.springs
    hub_link = model.hub_link
    rest = model.rest
    stiffness = model.stiffness
    damping = model.damping
    offset = model.offset
    air = model.air
    tmax = 0.0
    p_diss = 0.0
    for s in range(k0, k1):
        if hub_link[s]:
            continue
        i = springs[s, 0]
        j = springs[s, 1]
        t, u0, u1, u2, lf, ldot, stretch = spring_force(
            (x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]),
            (v[j, 0] - v[i, 0], v[j, 1] - v[i, 1], v[j, 2] - v[i, 2]), 0.0,
            (rest[s], stiffness[s], damping[s], offset[s]))
        tension[s] = t
        tmax = max(tmax, t)
        p_diss += (t - stiffness[s] * max(stretch, 0.0)) * ldot
        a0 = a1 = a2 = 0.0
        if air and lf != 0.0:
            a0, a1, a2 = _segment_air(model, v, s, (i, j), (u0, u1, u2), lf, (v[i, 0], v[i, 1], v[i, 2]), lam)
            fa[i, 0] += a0; fa[i, 1] += a1; fa[i, 2] += a2
            fa[j, 0] += a0; fa[j, 1] += a1; fa[j, 2] += a2
        f[i, 0] += t * u0 + a0; f[i, 1] += t * u1 + a1; f[i, 2] += t * u2 + a2
        f[j, 0] += a0 - t * u0; f[j, 1] += a1 - t * u1; f[j, 2] += a2 - t * u2
    return tmax, p_diss


@njit(cache=True, fastmath={"reassoc", "nsz"})
def _sum(buf, start, c):
    """Σ buf[start … start + c − 1] (a row of the run scratch, :func:`_run_law`; start uint64: an
    unsigned index, else the wrap-around test keeps the loop scalar), reassociated (vector partial
    sums: order-dependent round-off)."""
    total = 0.0
    for r in range(c):
        total += buf[start + np.uint64(r)]
    return total


@njit(cache=True)
def _max_bits(bits, k, c, top):
    """max(top, bits[k … k+c−1]) (int64): the bit patterns of tensions >= +0 (or NaN), whose
    order is the order of the values, and an integer max vectorises where LLVM leaves a float
    max scalar. k (uint64) the first segment; start from top = 0 (+0.0)."""
    for r in range(c):
        top = max(top, bits[k + np.uint64(r)])
    return top


@njit(cache=True)
def _scatter(f, buf, rows, sign, chunk):
    """Adds a run chunk's end forces to one component f (n,) of the nodes. chunk = ((i0, s) uint64,
    (nq, c, stride)): segment (q, r), q < nq, r < c, joins nodes i0 + q stride + r and that + s;
    the force on its end i is entry q c + r of buf row rows[0], on its end j sign × that of row
    rows[1] (sign = ±1, exact). Row by row, node i0 + q stride + r gets its end-j force (from
    segment r − s) before its end-i force (from segment r), the order of the per-segment loop;
    three loops over node ranges, none with a conflict (vectorised)."""
    (i0, s_u), (nq, c, stride) = chunk
    s = np.int64(s_u)
    for q in range(nq):
        iq = i0 + np.uint64(q * stride)
        gi = np.uint64(rows[0] * ROWLEN + q * c)
        gj = np.uint64(rows[1] * ROWLEN + q * c)
        for r in range(min(s, c)):  # only end i
            f[iq + np.uint64(r)] += buf[gi + np.uint64(r)]
        for r in range(s, c):  # end j, then end i
            n = iq + np.uint64(r)
            f[n] = (f[n] + sign * buf[gj + np.uint64(r - s)]) + buf[gi + np.uint64(r)]
        for r in range(max(s, c), c + s):  # only end j
            f[iq + np.uint64(r)] += sign * buf[gj + np.uint64(r - s)]


@njit(cache=True, inline="always")
def _law(xs, vs, law, i, j, e):
    """``forces.spring_force`` of segment e joining nodes i, j: xs, vs 3 rows (n,) each of
    positions [m] and velocities [m/s]; law = (taut length l0 − offset [m], stiffness, damping)
    (m,) (:func:`_law_arrays`; its offset 0 gives the same stretch to the bit)."""
    x0, x1, x2 = xs
    v0, v1, v2 = vs
    taut, stiffness, damping = law
    return spring_force((x0[j] - x0[i], x1[j] - x1[i], x2[j] - x2[i]), (v0[j] - v0[i], v1[j] - v1[i], v2[j] - v2[i]),
                        0.0, (taut[e], stiffness[e], damping[e], 0.0))


@njit(cache=True)
def _law_arrays(model):
    """(taut length l0 − offset [m], stiffness [N/m], damping [N s/m]), each (m,): the rope law's
    data as the run loops read it (one array less than rest and offset)."""
    return model.rest - model.offset, model.stiffness, model.damping


ROW = tuple(np.uint64(k * ROWLEN) for k in range(13))
"""Offsets of the rows of the scratch (13 ROWLEN,): unsigned, as every index of the run
loops (numba tests a signed index for wrap-around, which keeps LLVM from vectorising), and
constant, so LLVM checks the aliasing of the scratch once, not row by row."""


@njit(cache=True, error_model="numpy")
def _run_law(xs, vs, law, chunk, tension, out, geometry=None):
    """The rope law (:func:`_law`) over a run chunk: chunk = ((i0, s, k) uint64, (nq, c, stride,
    length)), segment k + q length + r (q < nq, r < c) joins nodes i0 + q stride + r and that
    + s. Writes tension (m,) [N] and into out (13 ROWLEN,) at q c + r of its rows (:data:`ROW`):
    rows 0–2 the force T u on end i [N], 3 the dissipation rate (T − K s) l̇ [W]; with
    ``geometry`` given (any value but None: the air path) also rows 4 the straight length l [m]
    and 5–7 the unit vector u, for :func:`_run_air`.

    One function, two compiled versions: ``geometry`` omitted is typed ``Omitted(None)``, and
    numba prunes the ``is not None`` branch from the IR at compile time, so the air-free version
    has no geometry stores. Measured side by side against the former two copies (2026-11-28,
    ``benchmarks/net_kernel_ab.py``, thread CPU time): the same speed within the noise, air off and
    on, and the same trajectories to the bit; carrying the stores in the air-free path costs it 9–14 %."""
    (i0, s, k), (nq, c, stride, length) = chunk
    stiffness = law[1]
    for q in range(nq):
        iq = i0 + np.uint64(q * stride)
        kq = k + np.uint64(q * length)
        oq = np.uint64(q * c)
        for r in range(c):
            rr = np.uint64(r)
            e = kq + rr
            o = oq + rr
            t, u0, u1, u2, lf, ldot, stretch = _law(xs, vs, law, iq + rr, iq + rr + s, e)
            tension[e] = t
            out[o] = t * u0
            out[ROW[1] + o] = t * u1
            out[ROW[2] + o] = t * u2
            out[ROW[3] + o] = (t - stiffness[e] * max(stretch, 0.0)) * ldot
            if geometry is not None:
                out[ROW[4] + o] = lf
                out[ROW[5] + o] = u0
                out[ROW[6] + o] = u1
                out[ROW[7] + o] = u2


@njit(cache=True, error_model="numpy")
def _run_air(vs, air, chunk, out):
    """Rope aerodynamics (``_segment_air``, Eq. 5–10) over a run chunk (as :func:`_run_law`'s),
    after :func:`_run_law` (with geometry) filled rows 0–2 (T u), 4 (l), 5–7 (u) of out: vs 3 velocity
    rows (n,) [m/s]; air = (diameter (m,) [m], rho [kg/m³], wind (3,) [m/s]). Writes rows 8–10
    the half air force a [N] (0 for a zero-length segment), 11 its drag bound ½ ρ C_max d l |v|
    [kg/s]; turns rows 0–2 into the force on end i, T u + a, and rows 5–7 into the force on end
    j, a − T u. (A separate loop: fused with the law, the loop has too many arrays for the
    run-time alias checks LLVM accepts, and stays scalar; the grid path's :func:`_grid_bars` is
    fused: it reads positions, velocities and law data from one 2-D array each.)"""
    v0, v1, v2 = vs
    diameter, rho, wind = air
    w0, w1, w2 = wind[0], wind[1], wind[2]  # scalars: read in the loop, LLVM gathers them lane by lane
    (i0, s, k), (nq, c, stride, length) = chunk
    for q in range(nq):
        iq = i0 + np.uint64(q * stride)
        kq = k + np.uint64(q * length)
        oq = np.uint64(q * c)
        for r in range(c):
            rr = np.uint64(r)
            i = iq + rr
            j = i + s
            d = diameter[kq + rr]
            o = oq + rr
            lf = out[ROW[4] + o]
            vrel = (0.5 * (v0[i] + v0[j]) - w0, 0.5 * (v1[i] + v1[j]) - w1, 0.5 * (v2[i] + v2[j]) - w2)
            fx, fy, fz, vm = segment_aero_force((out[ROW[5] + o], out[ROW[6] + o], out[ROW[7] + o]), lf, vrel,
                                                rho, d)
            live = lf != 0.0
            a0 = 0.5 * fx if live else 0.0
            a1 = 0.5 * fy if live else 0.0
            a2 = 0.5 * fz if live else 0.0
            out[ROW[11] + o] = 0.5 * rho * C_MAX * d * lf * vm if live else 0.0
            tu0, tu1, tu2 = out[o], out[ROW[1] + o], out[ROW[2] + o]
            out[o] = tu0 + a0
            out[ROW[1] + o] = tu1 + a1
            out[ROW[2] + o] = tu2 + a2
            out[ROW[5] + o] = a0 - tu0
            out[ROW[6] + o] = a1 - tu1
            out[ROW[7] + o] = a2 - tu2
            out[ROW[8] + o] = a0
            out[ROW[9] + o] = a1
            out[ROW[10] + o] = a2


@njit(cache=True, error_model="numpy")
def _run_forces(model, rows, law, fs, lam, fas, run, buf):
    """Adds the tensions and, with air, the aerodynamics of a run (``run`` = (k0, nrows, length,
    a0, stride, s), :func:`spring_blocks`) to fs (3, n) [N] (and the air's to fas (3, n) [N],
    its drag bound to lam (n,) [kg/s]); writes their tension into rows[2] (m,) [N]. rows = (3
    position rows (n,) [m], 3 velocity rows (n,) [m/s], tension, its int64 view); law as
    :func:`_law`'s; buf (12 ROWLEN,) scratch. Returns (the largest tension's bit pattern
    (:func:`_max_bits`), the dissipation rate [W]).

    Chunk by chunk (whole rows while they fit in CHUNK, else pieces of one row): the law over
    contiguous node ranges (no gathers), then the forces added to the nodes (:func:`_scatter`:
    each node in the per-segment loop's order)."""
    xs, vs, tension, bits = rows
    k0, nrows, length, a0, stride, s = run
    per = max(1, CHUNK // length)  # rows per chunk
    width = min(length, CHUNK)  # segments per row of a chunk
    tbits = 0
    p_diss = 0.0
    for q0 in range(0, nrows, per):
        nq = min(per, nrows - q0)
        for r0 in range(0, length, width):
            c = min(width, length - r0)
            i0 = np.uint64(a0 + q0 * stride + r0)
            k = np.uint64(k0 + q0 * length + r0)
            chunk = ((i0, np.uint64(s), k), (nq, c, stride, length))
            ends = ((i0, np.uint64(s)), (nq, c, stride))
            if model.air:
                _run_law(xs, vs, law, chunk, tension, buf, True)
                _run_air(vs, (model.diameter, model.rho, model.wind), chunk, buf)
                for comp in range(3):
                    _scatter(fs[comp], buf, (comp, 5 + comp), 1.0, ends)
                    _scatter(fas[comp], buf, (8 + comp, 8 + comp), 1.0, ends)
                _scatter(lam, buf, (11, 11), 1.0, ends)
            else:
                _run_law(xs, vs, law, chunk, tension, buf)
                for comp in range(3):
                    _scatter(fs[comp], buf, (comp, comp), -1.0, ends)
            tbits = _max_bits(bits, k, nq * c, tbits)  # whole rows or one row: contiguous
            p_diss += _sum(buf, ROW[3], nq * c)
    return tbits, p_diss


@njit(cache=True, error_model="numpy")
def _hub_link_forces(model, state, f, lam, fa):
    """Adds the forces of the hub links (Eq. 12–19: rim point, wrap, tension, air) to f (n, 3)
    [N], their air loads also to fa (n, 3) [N]; updates their wrap (m,) [rad] and tension (m,)
    [N]. Returns (torque about +z on the hub [N m], largest hub-link tension [N], dashpot
    dissipation rate [W]); as :func:`_block_forces`, with l̇ the rate of the straight part (the
    wound part's rate is not in the dashpot, Eq. 12–19)."""
    x = state.x
    v = state.v
    hub = model.hub
    torque = 0.0
    tmax = 0.0
    p_diss = 0.0
    pt = np.empty(3)
    vt = np.empty(3)
    for s in model.links:
        j = model.springs[s, 1]
        gamma, w = hub_link_state(model, state, s, pt, vt)
        state.wrap[s] = w
        t, u0, u1, u2, lf, ldot, stretch = spring_force(
            (x[j, 0] - pt[0], x[j, 1] - pt[1], x[j, 2] - pt[2]), (v[j, 0] - vt[0], v[j, 1] - vt[1], v[j, 2] - vt[2]),
            model.r0 * abs(w), (model.rest[s], model.stiffness[s], model.damping[s], model.offset[s]))
        state.tension[s] = t
        tmax = max(tmax, t)
        p_diss += (t - model.stiffness[s] * max(stretch, 0.0)) * ldot
        f[hub, 0] += t * u0; f[hub, 1] += t * u1; f[hub, 2] += t * u2
        f[j, 0] -= t * u0; f[j, 1] -= t * u1; f[j, 2] -= t * u2
        # lever arm of the rim point: (T - c) x (t u), z component (Eq. 12-13)
        torque += t * ((pt[0] - x[hub, 0]) * u1 - (pt[1] - x[hub, 1]) * u0)
        if model.air and lf != 0.0:
            a0, a1, a2 = _segment_air(model, v, s, (hub, j), (u0, u1, u2), lf, (vt[0], vt[1], vt[2]), lam)
            f[hub, 0] += a0; f[hub, 1] += a1; f[hub, 2] += a2
            f[j, 0] += a0; f[j, 1] += a1; f[j, 2] += a2
            fa[hub, 0] += a0; fa[hub, 1] += a1; fa[hub, 2] += a2
            fa[j, 0] += a0; fa[j, 1] += a1; fa[j, 2] += a2
    return torque, tmax, p_diss


@njit(cache=True)
def _segment_forces(model, view, law, fs, lam, fas, buf):
    """Adds the forces of every segment that is not a hub link (runs by :func:`_run_forces`,
    the rest by :func:`_block_forces`, in the order of ``model.blocks``) to fs (3, n) [N], their
    air loads to fas (3, n) [N] and drag bounds to lam (n,) [kg/s]; writes their tension.
    ``view`` a DeployState whose x, v are the transposes of (3, n) arrays; law as :func:`_law`'s.
    Returns (the largest tension [N], the dissipation rate [W])."""
    xs = view.x.T
    vs = view.v.T
    rows = ((xs[0], xs[1], xs[2]), (vs[0], vs[1], vs[2]), view.tension, view.tension.view(np.int64))
    tmax = 0.0
    tbits = 0
    p_diss = 0.0
    for b in range(model.blocks.shape[0]):
        blk = model.blocks[b]
        if blk[5] > 0:
            tb, p = _run_forces(model, rows, law, fs, lam, fas, (blk[0], blk[1], blk[2], blk[3], blk[4], blk[5]), buf)
            tbits = max(tbits, tb)
        else:
            t, p = _block_forces(model, view, fs.T, lam, fas.T, blk[0], blk[0] + blk[1] * blk[2])
            tmax = max(tmax, t)
        p_diss += p
    return max(tmax, np.int64(tbits).view(np.float64)), p_diss


@njit(cache=True)
def _weights(model, fs):
    """fs[:, i] = m_i g, fs (3, n) [N]."""
    for k in range(3):
        for i in range(fs.shape[1]):
            fs[k, i] = model.mass[i] * model.gravity[k]


@njit(cache=True)
def _components(a):
    """The (3, n) copy of an (n, 3) array (one contiguous row per component)."""
    out = np.empty((3, a.shape[0]))
    for i in range(a.shape[0]):
        for k in range(3):
            out[k, i] = a[i, k]
    return out


@njit(cache=True)
def _soa_view(state):
    """(xs, vs, view): the (3, n) copies of the state's x, v and a DeployState seeing them as (n, 3)."""
    xs = _components(state.x)
    vs = _components(state.v)
    return xs, vs, DeployState(xs.T, vs.T, state.hub, state.wrap, state.tension, state.losses)


@njit(cache=True)
def net_forces(model, state, f, lam):
    """All forces on the net at one instant, Eq. (11): gravity + rope tensions (Eq. 1–4, hub
    links Eq. 12–19) + rope aerodynamics (Eq. 5–10). ``model`` a DeployModel, ``state`` a
    DeployState (its tension (m,) [N] is written and its wrap (m,) [rad] updated in place).
    Writes f (n, 3) [N]. Returns (torque about +z on the hub [N m], max tension [N]).

    lam (n,) [kg/s]: accumulates, per node, a Gershgorin bound of the drag's velocity
    derivative Σ_s ½ ρ C_max d l |v_s| (the caller divides by m).
    """
    xs, vs, view = _soa_view(state)
    fs = np.empty(xs.shape)
    fas = np.zeros(xs.shape)
    _weights(model, fs)
    tmax, _ = _segment_forces(model, view, _law_arrays(model), fs, lam, fas, np.empty(12 * ROWLEN))
    torque, tlink, _ = _hub_link_forces(model, view, fs.T, lam, fas.T)
    f[:, :] = fs.T
    return torque, max(tmax, tlink)


@njit(cache=True, fastmath={"reassoc", "nsz"})
def _air_work(fas, vs, fs, rate, mass):
    """The air's work terms of one step (before the update): (Σ fa·(2v + a f), Σ fa (3,),
    Σ m (2v + a f) (3,)), fa = fas, v = vs, f = fs (3, n), a = rate (n,) = dt / m [s/kg],
    mass (n,) [kg]; reassociated sums."""
    w_air = 0.0
    fa_sum = np.zeros(3)
    vc_sum = np.zeros(3)
    for k in range(3):
        fk, vk, ak = fas[k], vs[k], fs[k]
        sw = sf = sv = 0.0
        for i in range(fk.shape[0]):
            dv = 2.0 * vk[i] + rate[i] * ak[i]
            sw += fk[i] * dv
            sf += fk[i]
            sv += mass[i] * dv
        w_air += sw
        fa_sum[k] = sf
        vc_sum[k] = sv
    return w_air, fa_sum, vc_sum


@njit(cache=True)
def _drag_number(lam, rate, top):
    """max(top, max λ_i a_i) (the drag stability number λ dt, λ = lam (n,) [kg/s] >= 0, a =
    rate (n,) = dt / m [s/kg]); resets lam to 0."""
    for i in range(lam.shape[0]):
        lam[i] *= rate[i]
    top = max(top, np.int64(_max_bits(lam.view(np.int64), np.uint64(0), lam.shape[0], 0)).view(np.float64))
    lam[:] = 0.0
    return top


@njit(cache=True)
def _update(xs, vs, fs, rate, mass, gravity, dt):
    """Symplectic Euler on (3, n) arrays: v += a f, x += dt v (a = rate = dt / m (n,) [s/kg]),
    then fs reset to the weights m g [N] for the next step."""
    for k in range(3):
        x, v, f, g = xs[k], vs[k], fs[k], gravity[k]
        for i in range(x.shape[0]):
            v[i] += rate[i] * f[i]
            x[i] += dt * v[i]
            f[i] = mass[i] * g


@njit(cache=True)
def _grid_shape(model):
    """(W, B): W when the segments are a W × H grid of knots in the traction net's two blocks (all
    horizontal bars as H rows of W − 1, s = 1, then all vertical bars as one layer, s = W), no
    hub, and W <= CHUNK; B = max(1, TILE // W) knot rows per tile of :func:`_grid_step`. (0, 0)
    for any other net."""
    b = model.blocks
    if model.hub >= 0 or b.shape[0] != 2 or b[0, 5] != 1 or b[1, 1] != 1 or b[1, 4] != 0:
        return 0, 0
    w, h = b[0, 4], b[0, 1]
    if w > CHUNK or w < 2 or b[0, 0] != 0 or b[0, 2] != w - 1 or b[0, 3] != 0:
        return 0, 0
    if b[1, 0] != h * (w - 1) or b[1, 2] != (h - 1) * w or b[1, 3] != 0 or b[1, 5] != w:
        return 0, 0
    return w, max(1, TILE // w)


@njit(cache=True)
def _grid_law(model, law, w):
    """The bars' data of a grid net indexed by their end-i knot: ((4, n), (4, n)) for the
    horizontal and the vertical bars, rows taut length l0 − offset [m], stiffness [N/m], damping
    [N s/m], diameter [m] (:func:`_law_arrays`). Where no bar is (a knot at a row's end; the last
    row, vertically) taut length +inf, the rest 0: slack, no air load (T = 0, a = 0). With them
    a tile's bars are one loop over its knots, reading one array (:func:`_grid_bars`)."""
    n = model.mass.shape[0]
    hl, vl = np.empty((4, n)), np.empty((4, n))
    _by_knot((hl[0], vl[0]), law[0], w, np.inf)
    _by_knot((hl[1], vl[1]), law[1], w, 0.0)
    _by_knot((hl[2], vl[2]), law[2], w, 0.0)
    _by_knot((hl[3], vl[3]), model.diameter, w, 0.0)
    return hl, vl


@njit(cache=True)
def _by_knot(out, data, w, pad):
    """out = (horizontal, vertical) (n,): the segment data (m,) of a grid's bars at their end-i
    knot (:func:`_grid_law`), ``pad`` where no bar is."""
    n = out[0].shape[0]
    first_up = n - n // w  # the vertical bars' first segment: H (W − 1); (H − 1) W of them
    for row in range(n // w):
        out[0][row * w:row * w + w - 1] = data[row * (w - 1):row * (w - 1) + w - 1]
        out[0][row * w + w - 1] = pad
    out[1][:n - w] = data[first_up:first_up + n - w]
    out[1][n - w:] = pad


@njit(cache=True, error_model="numpy")
def _grid_bars(xv, law, span, out, aero=None):
    """The rope law (:func:`_law`) and, with ``aero`` = (rho [kg/m³], wind (3,) [m/s]) given, the
    aerodynamics (as :func:`_run_air`) of the bars from knots a … a + n − 1 to knot + s (span =
    (a, s, n, base) uint64; law (4, n) as :func:`_grid_law`'s, by knot; xv = (xs, vs) (3, n) [m],
    [m/s]). Writes at base + l of out's rows (:data:`ROW`): 0–2 T u [N], 3 the dissipation rate
    [W], 12 T [N]; with air 8–10 the half air force a [N], 11 its drag bound [kg/s]. One loop:
    positions, velocities and law data each one 2-D array, so LLVM's run-time alias checks stay
    few and it vectorises the law and the air together (no geometry rows)."""
    xs, vs = xv
    a, s, n, base = span
    if aero is not None:  # the wind as scalars: read in the loop, LLVM gathers it lane by lane
        rho, wind = aero
        w0, w1, w2 = wind[0], wind[1], wind[2]
    for l in range(n):
        lu = np.uint64(l)
        i = a + lu
        j = i + s
        o = base + lu
        t, u0, u1, u2, lf, ldot, stretch = spring_force(
            (xs[0, j] - xs[0, i], xs[1, j] - xs[1, i], xs[2, j] - xs[2, i]),
            (vs[0, j] - vs[0, i], vs[1, j] - vs[1, i], vs[2, j] - vs[2, i]), 0.0,
            (law[0, i], law[1, i], law[2, i], 0.0))
        out[ROW[12] + o] = t
        out[o] = t * u0
        out[ROW[1] + o] = t * u1
        out[ROW[2] + o] = t * u2
        out[ROW[3] + o] = (t - law[1, i] * max(stretch, 0.0)) * ldot
        if aero is not None:
            d = law[3, i]
            vrel = (0.5 * (vs[0, i] + vs[0, j]) - w0, 0.5 * (vs[1, i] + vs[1, j]) - w1,
                    0.5 * (vs[2, i] + vs[2, j]) - w2)
            fx, fy, fz, vm = segment_aero_force((u0, u1, u2), lf, vrel, rho, d)
            live = lf != 0.0
            out[ROW[8] + o] = 0.5 * fx if live else 0.0
            out[ROW[9] + o] = 0.5 * fy if live else 0.0
            out[ROW[10] + o] = 0.5 * fz if live else 0.0
            out[ROW[11] + o] = 0.5 * rho * C_MAX * d * lf * vm if live else 0.0


@njit(cache=True)
def _fill(buf, rows, span, value):
    """buf[ROW[r] + i] = value for rows = (first, stop) (r in first … stop − 1), span = (start,
    stop) (i likewise)."""
    for r in range(rows[0], rows[1]):
        for i in range(span[0], span[1]):
            buf[ROW[r] + np.uint64(i)] = value


@njit(cache=True)
def _shift_down(buf, rows, start, w):
    """buf[ROW[r] + i] = buf[ROW[r] + start + i], i < w, r < rows: a tile's last row of vertical
    bars becomes the next tile's row below."""
    for r in range(rows):
        for i in range(w):
            buf[ROW[r] + np.uint64(i)] = buf[ROW[r] + np.uint64(start + i)]


@njit(cache=True)
def _grid_pads(hb, w, nr, air):
    """The entries q W (q <= nr) of hb, where no bar is (a row's end: the padded bar of
    :func:`_grid_law`): rows 0–3 (T u, dissipation) and 12 (tension) +0.0, with air rows 8–11
    (a, λ) −0.0. A knot at a row's start reads them as its missing end j: f + −1 × (+0.0) = f, or
    with air f + (−0.0 − (+0.0)) = f; one at a row's end as its missing end i: f + (+0.0), or
    f + (+0.0 + −0.0), = f but for f = −0.0, which needs a −0.0 weight component m g. The air's
    share and λ, from +0.0, + −0.0: unchanged. Rows 3 and 12 enter the tile's sums as zeros."""
    for q in range(nr + 1):
        _fill(hb, (0, 4), (q * w, q * w + 1), 0.0)
        _fill(hb, (12, 13), (q * w, q * w + 1), 0.0)
        if air:
            _fill(hb, (8, 12), (q * w, q * w + 1), -0.0)


@njit(cache=True, error_model="numpy")
def _grid_tile_law(xv, laws, hb, vb, tile):
    """The bars of a tile (:func:`_grid_bars`; tile = (a uint64, (nr, nv, W), aero or None):
    knots a … a + nr W − 1, nv rows of them with bars up): the horizontal ones into hb (the bar
    from knot a + l at 1 + l: that knot reads its end-i force at l + 1, the next its end-j force
    there), the vertical ones into vb from W (knot a + l's end i at W + l). laws as
    :func:`_grid_law`'s. Returns (largest tension's bit pattern, dissipation rate [W])."""
    a, (nr, nv, w), aero = tile
    wu, one = np.uint64(w), np.uint64(1)
    _grid_bars(xv, laws[0], (a, one, np.uint64(nr * w - 1), one), hb, aero)
    _grid_pads(hb, w, nr, aero is not None)
    tbits = _max_bits(hb.view(np.int64), ROW[12], nr * w, 0)
    p_diss = _sum(hb, ROW[3], nr * w)
    if nv > 0:
        _grid_bars(xv, laws[1], (a, wu, np.uint64(nv * w), wu), vb, aero)
        tbits = _max_bits(vb.view(np.int64), ROW[12] + wu, nv * w, tbits)
        p_diss += _sum(vb, ROW[3] + wu, nv * w)
    return tbits, p_diss


@njit(cache=True)
def _grid_tensions(tension, hb, vb, tile):
    """Copies the tensions [N] of a grid tile's bars from row 12 of hb and vb (as
    :func:`_grid_tile_law` fills them) into tension (m,): tile = ((k, kv) uint64, (nr, nv, W)),
    its first horizontal and vertical bar, its knot rows, how many of them have bars up."""
    (k, kv), (nr, nv, w) = tile
    for q in range(nr):
        for c in range(w - 1):
            tension[k + np.uint64(q * (w - 1) + c)] = hb[ROW[12] + np.uint64(1 + q * w + c)]
    for lv in range(nv * w):
        tension[kv + np.uint64(lv)] = vb[ROW[12] + np.uint64(w + lv)]


@njit(cache=True, error_model="numpy")
def _grid_update(xs, vs, mg, rate, hb, vb, tile, dt):
    """Air off: the forces on the knots a … a + n − 1 of a grid tile (tile = (a, n, W) uint64) in
    the per-segment loop's order — the weight m g, end j then end i of the horizontal bars (knot
    a + l at l, l + 1 of hb's rows 0–2), end j of the vertical bars from the row below (vb at l),
    end i of those to the row above (vb at W + l) — then symplectic Euler on them: v += a f,
    x += dt v. xs, vs (3, n) [m], [m/s]; mg = (mass (n,) [kg], gravity (3,) [m/s²]); rate (n,)
    a = dt / m [s/kg]."""
    a, n, w = tile
    mass, gravity = mg
    one = np.uint64(1)
    for comp in range(3):
        o = ROW[comp]
        g = gravity[comp]
        for l in range(n):
            lu = np.uint64(l)
            node = a + lu
            f = (mass[node] * g + -1.0 * hb[o + lu]) + hb[o + lu + one]
            f = (f + -1.0 * vb[o + lu]) + vb[o + w + lu]
            vn = vs[comp, node] + rate[node] * f
            vs[comp, node] = vn
            xs[comp, node] += dt * vn


@njit(cache=True, error_model="numpy")
def _grid_update_air(state, mg, rate, bufs, tile, dt):
    """:func:`_grid_update` with air (state = (xs, vs), bufs = (hb, vb, nb)): per knot the force
    as :func:`_run_forces` adds it (end j then end i: a − T u and T u + a, formed from rows 8–10
    and 0–2 as :func:`_run_air` forms them), the air's share fa (rows 8–10, from 0) into nb's
    rows 0–2, the velocity sum 2 v + a f before the update into rows 3–5 (for the air's work, as
    :func:`_air_work`), and its drag bound λ (row 11, from 0) times a into row 6."""
    a, n, w = tile
    xs, vs = state
    hb, vb, nb = bufs
    mass, gravity = mg
    one = np.uint64(1)
    for comp in range(3):
        o, oa, g = ROW[comp], ROW[8 + comp], gravity[comp]
        for l in range(n):
            lu = np.uint64(l)
            node = a + lu
            haj, hai, vaj, vai = hb[oa + lu], hb[oa + lu + one], vb[oa + lu], vb[oa + w + lu]
            f = (mass[node] * g + (haj - hb[o + lu])) + (hb[o + lu + one] + hai)
            f = (f + (vaj - vb[o + lu])) + (vb[o + w + lu] + vai)
            nb[ROW[comp] + lu] = (((0.0 + haj) + hai) + vaj) + vai
            vo = vs[comp, node]
            nb[ROW[3 + comp] + lu] = 2.0 * vo + rate[node] * f
            vn = vo + rate[node] * f
            vs[comp, node] = vn
            xs[comp, node] += dt * vn
    for l in range(n):
        lu = np.uint64(l)
        lam = (0.0 + hb[ROW[11] + lu]) + hb[ROW[11] + lu + one]
        nb[ROW[6] + lu] = ((lam + vb[ROW[11] + lu]) + vb[ROW[11] + w + lu]) * rate[a + lu]


@njit(cache=True, fastmath={"reassoc", "nsz"})
def _grid_air_sums(nb, mass, tile):
    """A tile's terms of the air's work (:func:`_air_work`): (Σ fa·(2v + a f), Σ fa (3,),
    Σ m (2v + a f) (3,)) over its knots a … a + n − 1 (tile = (a, n) uint64; fa and 2v + a f in
    nb's rows 0–2 and 3–5 from 0, :func:`_grid_update_air`; mass (n,) [kg]); one loop,
    reassociated (vector partial sums: order-dependent round-off)."""
    a, n = tile
    w_air = f0 = f1 = f2 = m0 = m1 = m2 = 0.0
    for l in range(n):
        lu = np.uint64(l)
        fa0, fa1, fa2 = nb[lu], nb[ROW[1] + lu], nb[ROW[2] + lu]
        dv0, dv1, dv2 = nb[ROW[3] + lu], nb[ROW[4] + lu], nb[ROW[5] + lu]
        m = mass[a + lu]
        w_air += fa0 * dv0 + fa1 * dv1 + fa2 * dv2
        f0 += fa0
        f1 += fa1
        f2 += fa2
        m0 += m * dv0
        m1 += m * dv1
        m2 += m * dv2
    return w_air, (f0, f1, f2), (m0, m1, m2)


@njit(cache=True, error_model="numpy")
def _grid_air_work(nb, mass, tile, acc):
    """Adds a tile's terms of the air's work (:func:`_grid_air_sums`) to acc[0], acc[1:4],
    acc[4:7], and its largest drag number λ a (nb's row 6) to acc[7] (tile = (a, n) uint64)."""
    w_air, fa, mv = _grid_air_sums(nb, mass, tile)
    acc[0] += w_air
    for comp in range(3):
        acc[1 + comp] += fa[comp]
        acc[4 + comp] += mv[comp]
    top = np.int64(_max_bits(nb.view(np.int64), ROW[6], tile[1], 0)).view(np.float64)
    acc[7] = max(acc[7], top)


@njit(cache=True, error_model="numpy")
def _grid_step(soa, laws, bufs, grid, dt):
    """One symplectic-Euler step of a grid net (:func:`_grid_shape`; grid = (W, H, B, last step?,
    air)), tile by tile of B knot rows: the laws of their bars (:func:`_grid_tile_law`; vb's first
    W entries hold the row below's bars, none below the first row, −0.0 above the last), then the
    tile's forces and update (:func:`_grid_update`, :func:`_grid_update_air` and
    :func:`_grid_air_work`); the last step copies the tensions out. soa = (xs, vs (3, n) [m],
    [m/s], (mass, gravity), rate (n,), tension (m,) [N]); laws = (as :func:`_grid_law`'s, (rho,
    wind)); bufs = (hb, vb, nb, acc (8,), zeroed by the caller). Returns (largest tension [N],
    dissipation rate [W])."""
    w, h, b, last, air = grid
    xs2, vs2, mg, rate, tension = soa
    hb, vb, nb, acc = bufs
    nrow = 12 if air else 3
    _fill(vb, (0, 3), (0, w), 0.0)
    if air:
        _fill(vb, (8, 12), (0, w), -0.0)
    tbits = 0
    p_diss = 0.0
    for r0 in range(0, h, b):
        nr = min(b, h - r0)
        nv = min(nr, h - 1 - r0)
        a = np.uint64(r0 * w)
        kv = np.uint64(h * (w - 1)) + a
        if air:
            tb, p = _grid_tile_law((xs2, vs2), laws[0], hb, vb, (a, (nr, nv, w), laws[1]))
        else:
            tb, p = _grid_tile_law((xs2, vs2), laws[0], hb, vb, (a, (nr, nv, w), None))
        tbits = max(tbits, tb)
        p_diss += p
        if nv < nr:
            _fill(vb, (0, nrow), (nr * w, nr * w + w), -0.0)
        if last:
            _grid_tensions(tension, hb, vb, ((np.uint64(r0 * (w - 1)), kv), (nr, nv, w)))
        tile = (a, np.uint64(nr * w), np.uint64(w))
        if air:
            _grid_update_air((xs2, vs2), mg, rate, (hb, vb, nb), tile, dt)
            _grid_air_work(nb, mg[0], (a, np.uint64(nr * w)), acc)
        else:
            _grid_update(xs2, vs2, mg, rate, hb, vb, tile, dt)
        _shift_down(vb, nrow, nr * w, w)
    return np.int64(tbits).view(np.float64), p_diss


@njit(cache=True, error_model="numpy")
def _advance_grid(model, state, n_steps, dt):
    """:func:`advance` for a grid net (:func:`_grid_shape`): :func:`_grid_step`."""
    mass = model.mass
    w, b = _grid_shape(model)
    xs, vs, view = _soa_view(state)
    rate = dt / mass
    laws = (_grid_law(model, _law_arrays(model), w), (model.rho, model.wind))
    soa = (xs, vs, (mass, model.gravity), rate, view.tension)
    bufs = (np.empty(13 * ROWLEN), np.empty(13 * ROWLEN), np.empty(7 * ROWLEN), np.zeros(8))
    inv_m = 1.0 / mass.sum()
    peak = 0.0
    for step in range(n_steps):
        grid = (w, mass.shape[0] // w, b, step + 1 == n_steps, model.air)
        tmax, p_diss = _grid_step(soa, laws, bufs, grid, dt)
        peak = max(peak, tmax)
        state.losses[0] += dt * p_diss
        if model.air:
            acc = bufs[3]
            state.losses[1] += 0.5 * dt * (acc[0] - inv_m * (acc[1] * acc[4] + acc[2] * acc[5] + acc[3] * acc[6]))
            acc[:7] = 0.0
    state.x[:, :] = xs.T
    state.v[:, :] = vs.T
    return peak, bufs[3][7]


@njit(cache=True, error_model="numpy")
def advance(model, state, n_steps, dt):
    """Advance ``state`` (DeployState) of ``model`` (DeployModel) ``n_steps`` steps of ``dt``
    [s] in place (symplectic Euler); ``state.tension`` holds the tensions of the last force
    evaluation (one step old).

    Returns (largest segment tension seen during the call [N], largest drag stability number
    λ dt, λ = drag velocity-derivative bound / m; the lagged-velocity update needs λ dt <= 2).
    Adds to ``state.losses`` (2,) [J] the dashpots' dissipation, booked as its power at the
    step's lagged velocities × dt (a left sum, first order in dt, as the collide kernel's rope
    dashpots), and the air's work on the motion about the centre of mass, booked exactly: the
    step changes that kinetic energy by Σ F_i·(v̄_i − v̄_c) dt, v̄ the mean of the velocities
    before and after it, and the weights' share of that sum is zero.
    """
    if _grid_shape(model)[0] > 0:
        return _advance_grid(model, state, n_steps, dt)
    mass = model.mass
    xs, vs, view = _soa_view(state)
    fs = np.empty(xs.shape)
    fas = np.zeros(xs.shape)
    lam = np.zeros(mass.shape[0])
    buf = np.empty(12 * ROWLEN)
    law = _law_arrays(model)
    rate = dt / mass
    _weights(model, fs)
    peak = 0.0
    drag_number = 0.0
    inv_m = 1.0 / mass.sum()
    losses = state.losses
    for step in range(n_steps):
        tmax, p_diss = _segment_forces(model, view, law, fs, lam, fas, buf)
        torque, tlink, q_diss = _hub_link_forces(model, view, fs.T, lam, fas.T)
        peak = max(peak, tmax, tlink)
        losses[0] += dt * (p_diss + q_diss)
        if model.air:
            w_air, fa_sum, vc_sum = _air_work(fas, vs, fs, rate, mass)
            losses[1] += 0.5 * dt * (w_air - inv_m * (fa_sum[0] * vc_sum[0] + fa_sum[1] * vc_sum[1]
                                                      + fa_sum[2] * vc_sum[2]))
            fas[:, :] = 0.0
            drag_number = _drag_number(lam, rate, drag_number)  # lam stays 0 without air
        _update(xs, vs, fs, rate, mass, model.gravity, dt)
        if model.hub >= 0:
            state.hub[1] += dt * torque / model.hub_inertia
            state.hub[0] += dt * state.hub[1]
    state.x[:, :] = xs.T
    state.v[:, :] = vs.T
    return peak, drag_number
