"""The rotary net's hub: a rigid disc of radius r0 spinning about +z, and the warps that start
on its rim and may wind onto it (paper §III-B, Eq. (12)–(13), (17)–(19)).

Model (lumped-mass form of the paper's hybrid model):
- The hub's centre is an ordinary node (its translation obeys Eq. (11) with the hub mass);
  its spin ω about the fixed axis +z obeys J ω̇ = Σ (r × F)·ẑ, Eq. (12)–(13) with M = 0
  (no control torque). Departure: the hub does not tilt (spin axis stays +z); the torque
  components about x and y are taken by that constraint.
- Each hub link (the segment from the rim to a warp's first node) is fixed to the rim at the
  anchor angle β = θ + β0. While the rope's radial declination |φ| < π/2 it runs straight from
  the anchor; when it would enter the hub (|φ| reaches π/2) it wraps on the rim: it leaves the
  rim tangentially at γ = β + ϕ, ϕ being the signed wound angle (Eq. (18): free length +
  r0 |ϕ| = total length of the link). The wound part is fixed to the hub (no slip); the
  link's length is the geodesic |p - T| + r0 |ϕ|, whose rate is û·(v_p - v_T) with v_T the
  hub's material velocity at the tangent point T — the lumped-mass form of Eq. (19).
  The force at T has lever arm r0 sin φ about the centre (|sin φ| = 1 while wound, Eq. (17)).
- The hub is a short cylinder of axial length H, the warps anchored at mid-height. The wrap
  is computed in the hub plane (projection along z; exact for a rope lying in that plane) and
  tracked by continuity (ϕ may exceed 2π). A rope whose first node is more than H/2 off the
  hub plane runs over the hub's end face, straight from the anchor (no winding; a wound rope
  slips off the end at that instant). Departure from the paper, whose Eq. (17)–(19) are planar:
  with air loads the net trails far behind the drag-free hub and the planar wrap has no meaning.
- Only the first segment of a warp winds: if the hub winds a warp past its first node (the
  node reaches the rim), the model no longer represents it; the stage logs a warning when a
  warp's first node enters the hub (``deploy.hub_nodes_inside``). Net–hub contact is not
  modelled.
"""

from __future__ import annotations

import math

from numba import njit

TWO_PI = 2.0 * math.pi


@njit(cache=True)
def wrap_geometry(qx, qy, beta, r0, wrap_prev):
    """Where a hub link leaves the rim. Returns (γ [rad], ϕ [rad]).

    qx, qy : position of the warp's first node relative to the hub centre, projected on the
    hub plane [m]; beta : world angle of the anchor [rad]; r0 : hub radius [m];
    wrap_prev : wound angle at the previous step [rad] (sign = winding sense, + about +z).
    Straight link (ϕ = 0, γ = β) while q·e(β) >= r0 (|φ| <= π/2). Wound link: γ is the tangent
    point from q on the winding side, ϕ = γ - β taken on the branch nearest ``wrap_prev``.
    If the node's projection is inside the rim (|q| <= r0, tangent undefined) the link keeps
    its wound angle for that step.
    """
    cb = math.cos(beta)
    sb = math.sin(beta)
    if wrap_prev == 0.0 and qx * cb + qy * sb >= r0:
        return beta, 0.0
    rq = math.sqrt(qx * qx + qy * qy)
    if rq <= r0:
        return beta + wrap_prev, wrap_prev
    if wrap_prev != 0.0:
        s = 1.0 if wrap_prev > 0.0 else -1.0
    else:
        s = 1.0 if cb * qy - sb * qx >= 0.0 else -1.0
    gamma = math.atan2(qy, qx) - s * math.acos(r0 / rq)
    w = gamma - beta
    w -= TWO_PI * math.floor((w - wrap_prev) / TWO_PI + 0.5)
    if s * w <= 0.0:  # unwound past the anchor: straight again
        return beta, 0.0
    return beta + w, w


@njit(cache=True)
def hub_link_state(model, state, s, out_t, out_vt):
    """Geometry of hub link s: writes the rim point T [m] into out_t (3,) and its material
    velocity v_T = v_c + ω ẑ × (T - c) [m/s] into out_vt (3,). Returns (γ, ϕ) [rad].
    ``model`` a ``net.kernels.DeployModel`` (hub node, warp node springs[s, 1], anchor β0,
    r0, H/2), ``state`` a ``DeployState`` (x, v (n, 3); hub = (θ, ω); wrap[s] the wound angle
    of the previous step, read only)."""
    x = state.x
    v = state.v
    hub = model.hub
    j = model.springs[s, 1]
    theta = state.hub[0]
    omega = state.hub[1]
    r0 = model.r0
    if abs(x[j, 2] - x[hub, 2]) > model.half_length:
        gamma, w = theta + model.anchor[s], 0.0
    else:
        gamma, w = wrap_geometry(x[j, 0] - x[hub, 0], x[j, 1] - x[hub, 1], theta + model.anchor[s], r0,
                                 state.wrap[s])
    cg = math.cos(gamma)
    sg = math.sin(gamma)
    out_t[0] = x[hub, 0] + r0 * cg
    out_t[1] = x[hub, 1] + r0 * sg
    out_t[2] = x[hub, 2]
    out_vt[0] = v[hub, 0] - omega * r0 * sg
    out_vt[1] = v[hub, 1] + omega * r0 * cg
    out_vt[2] = v[hub, 2]
    return gamma, w
