"""The compiled collision loop: rope springs + detection + contact + rigid missile, many steps per call.

One call of :func:`advance` integrates one output interval (``n_steps`` steps of ``dt``) with
symplectic Euler for the net nodes and the missile (``rigid_body.rigid_step``). Per step:

1. rope forces, Eq. (1)–(4) (tension only, with axial damping c l̇);
2. detection, paper §IV: every free net node and ``n_det`` equally spaced points per segment
   (the paper's "additional detection points") are transformed into the missile body frame B and
   tested against the missile's contact shapes (``missile.shapes``: signed distance to the surface);
   a point whose distance is below the rope radius is in contact with penetration
   δ = rope radius − distance (the paper's point–plane distance Eq. (26) generalised to curved
   surfaces; normal = surface normal, Eq. (27));
3. the segment test against thin fins (``missile.shapes.segment_fin_contact``): a rope segment
   whose centre line crosses a fin plate between detection points (not counting the chord of a
   rope wrapped on the body, which dips into the fin's root extension inside the body). With
   ``seg_test`` on it gets a contact force at the crossing, penetration = the centre line's depth
   past the fin edge (so the force starts from zero); with it off — or when a crossing is already
   deeper than the tunnelling limit when first seen — the crossing is only measured and counts
   as tunnelling;
4. normal force Eq. (28)–(29) with the damping model's χ fixed at first touch (v_k per contact),
   friction Eq. (32) regularised (``contact.law``); a segment point's force is shared by its two
   nodes with the linear weights (1 − s, s); the missile gets the opposite force at the surface
   point, and its torque about the CG;
5. rigid missile and free nodes advanced; held nodes (crop) do not move — the impulse they
   receive is accumulated so the momentum balance closes.

The missile's shapes come as the tuple ``shape`` of ``missile.shapes.pack_shapes`` (B frame);
a broad phase (bounding cylinder, body radius, fin-plane slabs) keeps the exact distance
functions to the few points that can touch.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flexnet_fe.collide.fpu import FTZ_DAZ, get_mxcsr, set_mxcsr
from flexnet_fe.collide.rigid_body import rigid_step
from flexnet_fe.contact.law import contact_potential, friction_force, hysteresis_factor, normal_force
from flexnet_fe.missile.shapes import body_closest_point, fin_closest_point, segment_fin_contact
from flexnet_fe.net.forces import rope_tension
from flexnet_fe.rigid import quat_to_matrix

# -- indices into the float parameter vector ``par`` -------------------------------------------
P_KN, P_EXP, P_E, P_MU, P_VREG, P_RROPE, P_TUNNEL, P_GX, P_GY, P_GZ, P_MMASS, P_VKMIN = range(12)
N_PAR = 12
# -- indices into the int parameter vector ``ipar`` --------------------------------------------
I_DAMP, I_NDET, I_SEGTEST, I_ALLOW = range(4)
N_IPAR = 4
# -- accumulators ``acc`` (float64), summed over the whole run unless said otherwise -----------
A_DISS_ROPE = 0  # energy dissipated by rope damping [J]
A_DISS_CONTACT = 1  # energy dissipated by contact damping [J]
A_DISS_FRICTION = 2  # energy dissipated by friction [J]
A_WORK_GRAVITY = 3  # work of gravity on net + missile [J]
A_PHELD = 4  # impulse received by held nodes, 3 components [N s] (4, 5, 6)
A_MAXPEN = 7  # largest penetration of the run [m]
A_MAXRATIO = 8  # largest (centre-line depth inside the part) / tunnelling limit of the run [-]
A_PEN_INT = 9  # largest penetration within the current call [m]
A_FB = 10  # Σ R^T F dt over the call, F the total force on the missile [N s] (10, 11, 12)
A_NCONTACT = 13  # largest number of simultaneous contacts within the call
A_SEGCROSS = 14  # segment/fin crossings measured but not resolved by a force (test off, or first seen too deep)
A_FCONTACT = 15  # Σ |F_contact| dt over the call [N s]
A_RATIO_PART = 16  # part id where the largest depth/limit ratio occurred
A_RATIO_SEG = 17  # 1 if that was a segment-test contact, else 0
A_RATIO_AT = 18  # where (B frame [m], 3 components 18..20) the largest ratio occurred
N_ACC = 21
# -- status codes -------------------------------------------------------------------------------
OK, TUNNEL, NONFINITE, EVENT_OVERFLOW = 0, 1, 2, 3


@njit(cache=True)
def rope_elastic_energy(length, rest_length, stiffness, offset):
    """Elastic energy ½ K max(l − (l0 − offset), 0)² [J] of one segment (the potential of
    ``net.forces.rope_tension``'s spring part)."""
    stretch = length - (rest_length - offset)
    return 0.5 * stiffness * stretch * stretch if stretch > 0.0 else 0.0


@njit(cache=True)
def rope_force(x, v, i, j, rest, k, c, off, fij):
    """Force of the rope segment i–j on node i [N] into ``fij`` (3,) with
    ``net.forces.rope_tension`` (Eq. (1)–(4), tension only, LINK167 offset ``off`` [m]);
    x, v [m, m/s] (n, 3). Returns (T [N], dissipated power [W]): the power of the rope force
    minus the rate of its elastic energy, (T − K·stretch)·l̇ (≥ 0 also when a fast shortening
    sets T = 0)."""
    d0 = x[j, 0] - x[i, 0]
    d1 = x[j, 1] - x[i, 1]
    d2 = x[j, 2] - x[i, 2]
    ln = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    stretch = ln - (rest - off)
    if stretch <= 0.0 or ln == 0.0:
        return 0.0, 0.0
    u0, u1, u2 = d0 / ln, d1 / ln, d2 / ln
    ldot = (v[j, 0] - v[i, 0]) * u0 + (v[j, 1] - v[i, 1]) * u1 + (v[j, 2] - v[i, 2]) * u2
    t = rope_tension(ln, rest, k, c, off, ldot)
    fij[0] = t * u0
    fij[1] = t * u1
    fij[2] = t * u2
    return t, (t - k * stretch) * ldot


@njit(cache=True)
def _mat_vec(r, a, out):
    """out = R a for R (3, 3), a (3,) (explicit: no BLAS call for 3 × 3)."""
    for k in range(3):
        out[k] = r[k, 0] * a[0] + r[k, 1] * a[1] + r[k, 2] * a[2]


@njit(cache=True)
def _mat_t_vec(r, a, out):
    """out = Rᵀ a for R (3, 3), a (3,)."""
    for k in range(3):
        out[k] = r[0, k] * a[0] + r[1, k] * a[1] + r[2, k] * a[2]


@njit(cache=True)
def _candidate(pb, rr, rad, r_body, fin_planes):
    """Broad phase without allocation: can a point at pb [m] (B) with contact radius ``rad`` touch
    the body (within r_body + rad of the axis; rr its squared axis distance) or a fin (within its
    half-thickness + rad of the fin's plane, inside its x range ± rad)?"""
    if rr <= (r_body + rad) ** 2:
        return True
    for fi in range(fin_planes.shape[0]):
        if fin_planes[fi, 4] - rad <= pb[0] <= fin_planes[fi, 5] + rad:
            dn = pb[0] * fin_planes[fi, 0] + pb[1] * fin_planes[fi, 1] + pb[2] * fin_planes[fi, 2] - fin_planes[fi, 3]
            if abs(dn) <= fin_planes[fi, 6] + rad:
                return True
    return False


@njit(cache=True)
def _closest(pb, rr, rad, r_body, fin_planes, shape):
    """``missile.shapes.closest_point`` restricted to the parts a point of contact radius ``rad``
    [m] can touch: the body of revolution only if the point is within r_body + rad of the axis
    (rr = its squared distance from the axis), a fin only if the point is within its half-thickness
    + rad of the fin's plane and inside its x range (± rad). Exact whenever the true distance is
    below ``rad``; otherwise it returns a distance ≥ rad (no contact) or +inf."""
    best = np.inf
    nb = np.zeros(3)
    sb = np.zeros(3)
    part = -1
    if rr <= (r_body + rad) ** 2:
        best, nb, sb, part = body_closest_point(pb, shape[0], shape[1], shape[2])
    for fi in range(fin_planes.shape[0]):
        fp = fin_planes[fi]
        if fp[4] - rad <= pb[0] <= fp[5] + rad:
            dn = pb[0] * fp[0] + pb[1] * fp[1] + pb[2] * fp[2] - fp[3]
            if abs(dn) <= fp[6] + rad:
                d, n_, q_ = fin_closest_point(pb, shape[3][fi], shape[4][fi], shape[5][fi], shape[6][fi])
                if d < best:
                    best, nb, sb, part = d, n_, q_, shape[7][fi]
    return best, nb, sb, part


@njit(cache=True)
def _segment_near_fin_plane(a, b, fin_planes):
    """Broad phase of the segment test: does segment a–b [m] (B) overlap some fin's x range and
    touch or cross its plane slab?"""
    for fi in range(fin_planes.shape[0]):
        fp = fin_planes[fi]
        if max(a[0], b[0]) < fp[4] or min(a[0], b[0]) > fp[5]:
            continue
        da = a[0] * fp[0] + a[1] * fp[1] + a[2] * fp[2] - fp[3]
        db = b[0] * fp[0] + b[1] * fp[1] + b[2] * fp[2] - fp[3]
        if da * db <= 0.0 or min(abs(da), abs(db)) <= fp[6]:
            return True
    return False


@njit(cache=True)
def _contact_force(v_w, delta, nb, sb, idx, det_touch, det_chi, mx, mv, w_w, r, m_cg_b, par, ipar,
                   f_out, c_w_out, fb_out, tmp):
    """Force of one contact, Eq. (28)–(29) and (32), given its geometry.

    v_w [m/s] (3,) velocity of the net point in W; delta [m] > 0 penetration; nb (3,) outward
    surface normal and sb [m] (3,) surface point, in B; idx its contact slot (first-touch state:
    det_touch, det_chi). Writes the force ON THE NET POINT [N] into f_out (W), the surface point
    into c_w_out (W) and the force ON THE MISSILE in B into fb_out; tmp (4, 3) scratch.
    Returns (normal-damping power [W], friction power [W]) dissipated."""
    nw = tmp[0]
    vrel = tmp[1]
    vt = tmp[2]
    ft = tmp[3]
    _mat_vec(r, nb, nw)
    for k in range(3):
        c_w_out[k] = sb[k] - m_cg_b[k]
    _mat_vec(r, c_w_out, vt)  # lever arm from the CG, W
    for k in range(3):
        c_w_out[k] = mx[k] + vt[k]
    # velocity of the net point relative to the missile material point under it
    vrel[0] = v_w[0] - mv[0] - (w_w[1] * vt[2] - w_w[2] * vt[1])
    vrel[1] = v_w[1] - mv[1] - (w_w[2] * vt[0] - w_w[0] * vt[2])
    vrel[2] = v_w[2] - mv[2] - (w_w[0] * vt[1] - w_w[1] * vt[0])
    vn = vrel[0] * nw[0] + vrel[1] * nw[1] + vrel[2] * nw[2]
    ddot = -vn  # penetration rate
    if not det_touch[idx]:
        det_touch[idx] = True
        # v_k: approach speed at first touch, Eq. (29). χ ∝ 1/v_k: a contact that starts with
        # (almost) no approach speed — a point sliding in from a neighbouring part — would get an
        # unbounded χ and, hit fast later, an unbounded damping force. Below the case's
        # ``damping_min_impact_speed`` the contact is therefore elastic (χ = 0): the models'
        # restitution relations do not hold for such contacts anyway.
        det_chi[idx] = hysteresis_factor(ipar[I_DAMP], par[P_E], ddot) if ddot > par[P_VKMIN] else 0.0
    fn = normal_force(delta, ddot, par[P_KN], par[P_EXP], det_chi[idx])
    fel = par[P_KN] * delta ** par[P_EXP]
    for k in range(3):
        vt[k] = vrel[k] - vn * nw[k]
    friction_force(fn, par[P_MU], vt, par[P_VREG], ft)
    for k in range(3):
        f_out[k] = fn * nw[k] + ft[k]
    _mat_t_vec(r, f_out, fb_out)
    for k in range(3):
        fb_out[k] = -fb_out[k]
    p_damp = (fn - fel) * ddot  # ≥ 0 while the damping force opposes the penetration rate
    p_fric = -(ft[0] * vt[0] + ft[1] * vt[1] + ft[2] * vt[2])
    return p_damp, p_fric


@njit(cache=True)
def _fin_event(idx, part, fb, pb, dt, det_fin, det_imp, det_pt, det_w, ev_fin, ev_pt, ev_imp, ev_w, nev):
    """Accumulate the impulse of contact ``idx`` on fin ``part − 2`` for the current interval
    (flushing the old fin's sum into the event buffer if the contact moved to another fin).
    Returns the new event count (−1 on overflow)."""
    fin = part - 2
    if det_fin[idx] >= 0 and det_fin[idx] != fin:
        nev = _flush_one(idx, det_fin, det_imp, det_pt, det_w, ev_fin, ev_pt, ev_imp, ev_w, nev)
        if nev < 0:
            return nev
    det_fin[idx] = fin
    mag = np.sqrt(fb[0] * fb[0] + fb[1] * fb[1] + fb[2] * fb[2]) * dt
    for k in range(3):
        det_imp[idx, k] += fb[k] * dt
        det_pt[idx, k] += mag * pb[k]
    det_w[idx] += mag
    return nev


@njit(cache=True)
def _flush_one(idx, det_fin, det_imp, det_pt, det_w, ev_fin, ev_pt, ev_imp, ev_w, nev):
    if nev >= ev_fin.shape[0]:
        return -1
    ev_fin[nev] = det_fin[idx]
    for k in range(3):
        ev_imp[nev, k] = det_imp[idx, k]
        ev_pt[nev, k] = det_pt[idx, k] / det_w[idx] if det_w[idx] > 0.0 else 0.0
        det_imp[idx, k] = 0.0
        det_pt[idx, k] = 0.0
    ev_w[nev] = det_w[idx]
    det_w[idx] = 0.0
    det_fin[idx] = -1
    return nev + 1


@njit(cache=True)
def _advance(n_steps, dt, x, v, node_mass, node_free, node_radius, seg, seg_rest, seg_k, seg_c, seg_off,
            det_touch, det_chi, det_fin, det_imp, det_pt, det_w,
            mx, mv, mq, mh, m_inv_inertia, m_cg_b, bbox, fin_planes, fin_limit,
            par, ipar, shape, acc, ev_fin, ev_pt, ev_imp, ev_w):
    """Advance net + missile ``n_steps`` steps of ``dt`` [s] in place. Returns (status, q, nev).

    Net: x, v [m, m/s] (n, 3) W; node_mass [kg] (n,); node_free (n,) bool; node_radius [m] (n,)
    contact radius of each node (rope radius; hub radius for a rotary hub); seg (ns, 2) int64;
    seg_rest [m], seg_k [N/m], seg_c [N s/m], seg_off [m] (ns,) (``NetModel`` fields). Only
    segments with a free end are passed; segment points have the rope radius ``par[P_RROPE]``.
    Contact state (one slot per detection point: n nodes, then ns × n_det segment points, then
    ns segment-test slots): det_touch bool, det_chi [s/m]; fin impulse accumulators det_fin int,
    det_imp [N s] (np, 3) in B, det_pt [N s m] (np, 3), det_w [N s] (np,).
    Missile: mx, mv [m, m/s] (3,) CG in W; mq (4,) attitude; mh [kg m²/s] (3,) angular momentum
    about the CG in W; m_inv_inertia (3, 3) in B; m_cg_b [m] (3,) CG in B; bbox (4,):
    (x_min, x_max, r_max, r_body) bounding cylinder of all shapes and radius of the body of
    revolution in B (each point's test grows them by the point's contact radius); fin_planes
    (nfin, 7): per fin (n_x, n_y, n_z, n·origin, x_min, x_max, half-thickness) in B — a point
    outside the body radius is tested only if it is within the half-thickness (+ radius) of a
    fin's plane and inside its x range (broad phase; ``scene.fin_planes``).
    fin_limit [m] (nfin,): tunnelling limit of each fin; the body's limit is ``par[P_TUNNEL] ×
    rope radius``. Tunnelling = the rope's centre line inside a part deeper than its limit
    (δ − contact radius > limit; for the segment test, its in-plane depth past the fin edge). acc: accumulators (``A_*``). Events (fin impulses flushed at
    the end of the call): ev_fin, ev_pt [m] B, ev_imp [N s] B, ev_w [N s]; nev = their count.
    status: OK, TUNNEL (penetration above the limit and not allowed), NONFINITE, EVENT_OVERFLOW.
    """
    n = x.shape[0]
    ns = seg.shape[0]
    ndet = ipar[I_NDET]
    npts = n + ns * ndet
    mmass = par[P_MMASS]
    g = np.array([par[P_GX], par[P_GY], par[P_GZ]])
    rrope = par[P_RROPE]
    body_limit = par[P_TUNNEL] * rrope
    f = np.zeros((n, 3))
    pbn = np.zeros((n, 3))  # node positions in B
    seg_near = np.zeros(ns, dtype=np.bool_)
    fij = np.zeros(3)
    fc = np.zeros(3)
    cw = np.zeros(3)
    fb = np.zeros(3)
    pw = np.zeros(3)
    vw = np.zeros(3)
    pb = np.zeros(3)
    pb_a = np.zeros(3)
    pb_b = np.zeros(3)
    tmp = np.zeros((4, 3))
    hb = np.zeros(3)
    w_b = np.zeros(3)
    w_w = np.zeros(3)
    fm = np.zeros(3)
    tm = np.zeros(3)
    q = mq.copy()
    nev = 0
    for k in range(A_FB, A_FB + 3):
        acc[k] = 0.0
    acc[A_PEN_INT] = 0.0
    acc[A_NCONTACT] = 0.0
    acc[A_FCONTACT] = 0.0
    for step in range(n_steps):
        r = quat_to_matrix(q)
        _mat_t_vec(r, mh, hb)
        _mat_vec(m_inv_inertia, hb, w_b)
        _mat_vec(r, w_b, w_w)
        for k in range(3):
            fm[k] = mmass * g[k]  # force on the missile, W
            tm[k] = 0.0  # torque about the CG, W
        for i in range(n):
            for k in range(3):
                f[i, k] = node_mass[i] * g[k]
        # 1. rope springs, Eq. (1)–(4)
        for e in range(ns):
            i = seg[e, 0]
            j = seg[e, 1]
            t, pdiss = rope_force(x, v, i, j, seg_rest[e], seg_k[e], seg_c[e], seg_off[e], fij)
            if t > 0.0:
                for k in range(3):
                    f[i, k] += fij[k]
                    f[j, k] -= fij[k]
                acc[A_DISS_ROPE] += pdiss * dt
        # 2.–4. detection and contact. Broad phase: every node in B once per step, and a
        # segment-level reject (all its points lie within |b − a| of either end)
        for i in range(n):
            for k in range(3):
                pw[k] = x[i, k] - mx[k]
            _mat_t_vec(r, pw, pb)
            for k in range(3):
                pbn[i, k] = pb[k] + m_cg_b[k]
        for e in range(ns):
            i = seg[e, 0]
            j = seg[e, 1]
            lab = np.sqrt((pbn[j, 0] - pbn[i, 0]) ** 2 + (pbn[j, 1] - pbn[i, 1]) ** 2 + (pbn[j, 2] - pbn[i, 2]) ** 2)
            ra = np.sqrt(pbn[i, 1] ** 2 + pbn[i, 2] ** 2)
            rb = np.sqrt(pbn[j, 1] ** 2 + pbn[j, 2] ** 2)
            seg_near[e] = not (max(pbn[i, 0], pbn[j, 0]) < bbox[0] - rrope or min(pbn[i, 0], pbn[j, 0]) > bbox[1] + rrope
                               or min(ra, rb) - lab > bbox[2] + rrope)
        ncontact = 0
        for idx in range(npts + ns):
            if idx < n:
                i = idx
                if not node_free[i]:
                    continue
                j = i
                s = 0.0
            else:
                e = (idx - n) // ndet if idx < npts else idx - npts
                if not seg_near[e]:
                    det_touch[idx] = False
                    continue
                i = seg[e, 0]
                j = seg[e, 1]
                s = ((idx - n) % ndet + 1.0) / (ndet + 1.0) if idx < npts else -1.0  # −1: segment test
            if s >= 0.0:
                for k in range(3):
                    pb[k] = (1.0 - s) * pbn[i, k] + s * pbn[j, k]
                # cheap reject: bounding cylinder of the missile in B, grown by the contact radius
                rad = node_radius[i] if idx < n else rrope
                rr = pb[1] * pb[1] + pb[2] * pb[2]
                if pb[0] < bbox[0] - rad or pb[0] > bbox[1] + rad or rr > (bbox[2] + rad) ** 2:
                    det_touch[idx] = False
                    continue
                if not _candidate(pb, rr, rad, bbox[3], fin_planes):
                    det_touch[idx] = False
                    continue
                dist, nb, sb, part = _closest(pb, rr, rad, bbox[3], fin_planes, shape)
                delta = rad - dist
                if delta <= 0.0:
                    det_touch[idx] = False
                    continue
                for k in range(3):
                    vw[k] = (1.0 - s) * v[i, k] + s * v[j, k]
                p_damp, p_fric = _contact_force(vw, delta, nb, sb, idx, det_touch, det_chi, mx, mv, w_w, r,
                                                m_cg_b, par, ipar, fc, cw, fb, tmp)
            else:
                # 3. segment test against the thin fins
                for k in range(3):
                    pb_a[k] = pbn[i, k]
                    pb_b[k] = pbn[j, k]
                if (pb_a[0] < bbox[0] and pb_b[0] < bbox[0]) or (pb_a[0] > bbox[1] and pb_b[0] > bbox[1]):
                    det_touch[idx] = False
                    continue
                # any point of the segment is at least min(r_a, r_b) − |b − a| from the axis
                lab = np.sqrt((pb_b[0] - pb_a[0]) ** 2 + (pb_b[1] - pb_a[1]) ** 2 + (pb_b[2] - pb_a[2]) ** 2)
                rmin = min(np.sqrt(pb_a[1] ** 2 + pb_a[2] ** 2), np.sqrt(pb_b[1] ** 2 + pb_b[2] ** 2))
                if rmin - lab > bbox[2] or not _segment_near_fin_plane(pb_a, pb_b, fin_planes):
                    det_touch[idx] = False
                    continue
                part, s, sb, depth, nb = segment_fin_contact(pb_a, pb_b, *shape)
                if part < 0 or sb[1] * sb[1] + sb[2] * sb[2] < bbox[3] * bbox[3]:
                    # no crossing, or only the chord of a rope wrapped on the body dipping through
                    # the fin's root extension inside the body: the body's point contacts hold it
                    det_touch[idx] = False
                    continue
                if ipar[I_SEGTEST] == 0 or (not det_touch[idx] and depth > fin_limit[part - 2]):
                    # measured only: with the test off, or when the crossing is already deeper than
                    # the tunnelling limit when first seen (the rope went through between two
                    # steps or two detection points: no force can resolve it), it is tunnelling
                    acc[A_SEGCROSS] += 1.0
                    ratio = depth / fin_limit[part - 2]
                    if ratio > acc[A_MAXRATIO]:
                        acc[A_MAXRATIO] = ratio
                        acc[A_RATIO_PART] = part
                        acc[A_RATIO_SEG] = 1.0
                        for k in range(3):
                            acc[A_RATIO_AT + k] = sb[k]
                    if ratio > 1.0 and ipar[I_ALLOW] == 0:
                        return TUNNEL, q, nev
                    continue
                # the crossing point is pushed out along ``nb`` (over the nearest free edge, or out
                # of the nearest face) with the penetration of the rope's CENTRE LINE, δ = depth:
                # the force then starts from zero when the centre line first crosses the plate. (With
                # the rope surface, δ = depth + r, it would start at K r^m — a jump of ~7 MN for the
                # paper's rope under the penalty rule, which injects energy.) The rope's own radius at
                # an edge is resolved by the detection points.
                delta = depth
                rad = 0.0
                for k in range(3):
                    vw[k] = (1.0 - s) * v[i, k] + s * v[j, k]
                p_damp, p_fric = _contact_force(vw, delta, nb, sb, idx, det_touch, det_chi, mx, mv, w_w, r,
                                                m_cg_b, par, ipar, fc, cw, fb, tmp)
            # common: apply the contact force (point shared by its nodes with weights 1 − s, s)
            ncontact += 1
            if delta > acc[A_MAXPEN]:
                acc[A_MAXPEN] = delta
            if delta > acc[A_PEN_INT]:
                acc[A_PEN_INT] = delta
            # tunnelling measure: depth of the rope's centre line inside the part (δ − radius)
            limit = fin_limit[part - 2] if part >= 2 else body_limit
            ratio = (delta - rad) / limit
            if ratio > acc[A_MAXRATIO]:
                acc[A_MAXRATIO] = ratio
                acc[A_RATIO_PART] = part
                acc[A_RATIO_SEG] = 1.0 if idx >= npts else 0.0
                for k in range(3):
                    acc[A_RATIO_AT + k] = sb[k]
            if ratio > 1.0 and ipar[I_ALLOW] == 0:
                return TUNNEL, q, nev
            wi = 1.0 - s
            for k in range(3):
                f[i, k] += wi * fc[k]
                f[j, k] += s * fc[k]
                fm[k] -= fc[k]
            # torque of −fc at the surface point cw about the CG
            lx = cw[0] - mx[0]
            ly = cw[1] - mx[1]
            lz = cw[2] - mx[2]
            tm[0] -= ly * fc[2] - lz * fc[1]
            tm[1] -= lz * fc[0] - lx * fc[2]
            tm[2] -= lx * fc[1] - ly * fc[0]
            acc[A_DISS_CONTACT] += p_damp * dt
            acc[A_DISS_FRICTION] += p_fric * dt
            acc[A_FCONTACT] += np.sqrt(fc[0] ** 2 + fc[1] ** 2 + fc[2] ** 2) * dt
            if part >= 2:
                nev = _fin_event(idx, part, fb, sb, dt, det_fin, det_imp, det_pt, det_w,
                                 ev_fin, ev_pt, ev_imp, ev_w, nev)
                if nev < 0:
                    return EVENT_OVERFLOW, q, 0
        if ncontact > acc[A_NCONTACT]:
            acc[A_NCONTACT] = ncontact
        # 5. integrate: missile, then free nodes (symplectic Euler); held nodes keep still
        _mat_t_vec(r, fm, fb)
        for k in range(3):
            acc[A_FB + k] += fb[k] * dt
            acc[A_WORK_GRAVITY] += mmass * g[k] * mv[k] * dt
        q = rigid_step(mx, mv, q, mh, fm, tm, mmass, m_inv_inertia, dt)
        for i in range(n):
            if node_free[i]:
                for k in range(3):
                    acc[A_WORK_GRAVITY] += node_mass[i] * g[k] * v[i, k] * dt
                    v[i, k] += dt * f[i, k] / node_mass[i]
                    x[i, k] += dt * v[i, k]
            else:
                for k in range(3):
                    acc[A_PHELD + k] += f[i, k] * dt
        if not (np.isfinite(mx[0]) and np.isfinite(mv[2])):
            return NONFINITE, q, nev
    for i in range(n):
        if not (np.isfinite(x[i, 0]) and np.isfinite(x[i, 1]) and np.isfinite(x[i, 2])):
            return NONFINITE, q, nev
    # flush the fin impulses of this interval
    for idx in range(det_fin.shape[0]):
        if det_fin[idx] >= 0:
            nev = _flush_one(idx, det_fin, det_imp, det_pt, det_w, ev_fin, ev_pt, ev_imp, ev_w, nev)
            if nev < 0:
                return EVENT_OVERFLOW, q, 0
    return OK, q, nev


@njit(cache=True)
def advance(n_steps, dt, x, v, node_mass, node_free, node_radius, seg, seg_rest, seg_k, seg_c, seg_off,
            det_touch, det_chi, det_fin, det_imp, det_pt, det_w,
            mx, mv, mq, mh, m_inv_inertia, m_cg_b, bbox, fin_planes, fin_limit,
            par, ipar, shape, acc, ev_fin, ev_pt, ev_imp, ev_w):
    """:func:`_advance` with subnormal floats flushed to zero (``collide.fpu``); same arguments
    and results. The caller's floating-point control register is restored on return."""
    old = get_mxcsr()
    set_mxcsr(old | np.uint32(FTZ_DAZ))
    out = _advance(n_steps, dt, x, v, node_mass, node_free, node_radius, seg, seg_rest, seg_k, seg_c, seg_off,
                   det_touch, det_chi, det_fin, det_imp, det_pt, det_w,
                   mx, mv, mq, mh, m_inv_inertia, m_cg_b, bbox, fin_planes, fin_limit,
                   par, ipar, shape, acc, ev_fin, ev_pt, ev_imp, ev_w)
    set_mxcsr(old)
    return out


@njit(cache=True)
def net_energy(x, v, node_mass, node_free, seg, seg_rest, seg_k, seg_off):
    """(kinetic [J], rope elastic [J]) of the net; held nodes are at rest."""
    ke = 0.0
    for i in range(x.shape[0]):
        if node_free[i]:
            ke += 0.5 * node_mass[i] * (v[i, 0] ** 2 + v[i, 1] ** 2 + v[i, 2] ** 2)
    pe = 0.0
    for e in range(seg.shape[0]):
        i = seg[e, 0]
        j = seg[e, 1]
        d = np.sqrt((x[j, 0] - x[i, 0]) ** 2 + (x[j, 1] - x[i, 1]) ** 2 + (x[j, 2] - x[i, 2]) ** 2)
        pe += rope_elastic_energy(d, seg_rest[e], seg_k[e], seg_off[e])
    return ke, pe


@njit(cache=True)
def contact_energy(x, node_free, node_radius, seg, ndet, mx, mq, m_cg_b, bbox, fin_planes, par, shape):
    """Elastic energy stored in the point contacts [J], Σ K_n δ^(m+1)/(m+1) (segment-test
    contacts are not included: they are short-lived and their share is within the step error)."""
    r = quat_to_matrix(mq)
    n = x.shape[0]
    e_c = 0.0
    pw = np.zeros(3)
    pb = np.zeros(3)
    for idx in range(n + seg.shape[0] * ndet):
        if idx < n:
            if not node_free[idx]:
                continue
            i = idx
            j = idx
            s = 0.0
        else:
            e = (idx - n) // ndet
            s = ((idx - n) % ndet + 1.0) / (ndet + 1.0)
            i = seg[e, 0]
            j = seg[e, 1]
        for k in range(3):
            pw[k] = (1.0 - s) * x[i, k] + s * x[j, k]
        for k in range(3):
            pb[k] = m_cg_b[k] + r[0, k] * (pw[0] - mx[0]) + r[1, k] * (pw[1] - mx[1]) + r[2, k] * (pw[2] - mx[2])
        rad = node_radius[i] if idx < n else par[P_RROPE]
        if pb[0] < bbox[0] - rad or pb[0] > bbox[1] + rad or pb[1] ** 2 + pb[2] ** 2 > (bbox[2] + rad) ** 2:
            continue
        dist, nb, sb, part = _closest(pb, pb[1] ** 2 + pb[2] ** 2, rad, bbox[3], fin_planes, shape)
        e_c += contact_potential(rad - dist, par[P_KN], par[P_EXP])
    return e_c
