"""The engagement: missile 6-DOF + fin actuators + autopilot + seeker + PN vs a turning aircraft.

One numba kernel advances the whole state with fixed-step classical RK4 (all blocks are
continuous-time, as in Zarchan's simulations) until the first closest approach (range rate
changes sign) or ``t_end``. The aircraft is evaluated in closed form. Frames: ``flexnet_fe.flight``.

State vector s, shape (N_STATE,):
    0:3   missile position in F [m]          3:6   missile velocity in F [m/s]
    6:10  attitude quaternion B→F (w,x,y,z)   10:13 body rates p, q, r [rad/s]
    13:17 fin deflections δ_0..δ_3 [rad]      17:21 fin rates [rad/s]
    21:23 three-loop integrator states x (pitch, yaw) [rad]
    23:26 seeker-filtered LOS rate Ω_f in F [rad/s]

Fin actuators: δ̈ = ω_a² (sat(δ_c) − δ) − 2 ζ_a ω_a δ̇ with the rate held at ±rate limit and the
deflection at ±position limit (mechanical stops: after each step the states are put back on the
stop; the history shows them against the limits). These are the physical limits of the actuator,
not numerical clamps.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from flexnet_fe.flight import aero as A
from flexnet_fe.flight.eom import euler_rates, quat_rate
from flexnet_fe.flight.guidance import closing_speed, first_order_lag_rate, los_rate, pn_command
from flexnet_fe.flight.target import level_turn
from flexnet_fe.rigid import quat_to_matrix

N_STATE = 26

# Parameter vector P (float64), built by flexnet_fe.flight.stage.build_parameters.
P_NAV = 0          # navigation constant N [-]
P_TAU_S = 1        # seeker time constant [s]
P_AMAX = 2         # acceleration command limit [m/s^2]
P_GCOMP = 3        # 1: add +g to the command
P_G = 4            # gravity [m/s^2]
P_MASS = 5         # [kg]
P_IXX = 6          # [kg m^2]
P_IYY = 7          # [kg m^2] (= I_zz)
P_KLIFT = 8        # damage multiplier on C_N alpha-terms
P_KMOM = 9         # damage multiplier on C_M alpha-terms
P_KCTRL = 10       # rudder effectiveness
P_KA = 11          # three-loop gains
P_WI = 12
P_KR = 13
P_KDC = 14
P_KPHI = 15        # roll gains
P_KP = 16
P_WACT = 17        # actuator [rad/s]
P_ZACT = 18
P_DMAX = 19        # [rad]
P_RMAX = 20        # [rad/s]
P_TSPEED = 21      # target speed [m/s]
P_TOMEGA = 22      # target turn rate [rad/s]
P_TSTART = 23      # turn start [s]
P_ALT0 = 24        # altitude of y_F = 0 [m]
P_MACH_MIN = 25    # lowest Mach of the aero model
N_PARAM = 26

# Diagnostics recorded with the history (index, column name with unit).
DIAG_COLUMNS = (
    "target_x_m", "target_y_m", "target_z_m",
    "accel_cmd_y_mps2", "accel_cmd_z_mps2", "accel_y_mps2", "accel_z_mps2",
    "alpha_rad", "alpha_yaw_rad", "mach", "range_m", "closing_speed_mps",
    "fin_cmd_pitch_rad", "fin_cmd_yaw_rad", "fin_cmd_roll_rad", "roll_angle_rad",
)
N_DIAG = len(DIAG_COLUMNS)

STATUS_CLOSEST = 0
STATUS_T_END = 1
STATUS_NONFINITE = 2
STATUS_SUBSONIC = 3
STATUS_OUT_OF_AIR_TABLE = 4


@njit(cache=True)
def _mat_vec(m, v):
    """m @ v for (3, 3) and (3,) without BLAS call overhead."""
    out = np.empty(3)
    for i in range(3):
        out[i] = m[i, 0] * v[0] + m[i, 1] * v[1] + m[i, 2] * v[2]
    return out


@njit(cache=True)
def _mat_t_vec(m, v):
    """m.T @ v for (3, 3) and (3,)."""
    out = np.empty(3)
    for i in range(3):
        out[i] = m[0, i] * v[0] + m[1, i] * v[1] + m[2, i] * v[2]
    return out


@njit(cache=True)
def _interp_air(alt, air):
    """Linear interpolation in the ISA table air = (alt0, dalt, n, rho..., a...) -> (ρ, a).
    The caller keeps ``alt`` inside the table (run_engagement stops when it leaves)."""
    alt0, dalt, n = air[0], air[1], int(air[2])
    x = (alt - alt0) / dalt
    i = int(math.floor(x))
    if i < 0:
        i = 0
    if i > n - 2:
        i = n - 2
    f = x - i
    rho = air[3 + i] * (1 - f) + air[3 + i + 1] * f
    a = air[3 + n + i] * (1 - f) + air[3 + n + i + 1] * f
    return rho, a


@njit(cache=True)
def derivative(t, s, P, aero, air, tgt, ds, diag):
    """Fill ds (shape (N_STATE,)) with ṡ at time t [s] and diag (shape (N_DIAG,)).

    tgt: (p0 (3), forward (3), centre (3)) of the aircraft, shape (9,).
    """
    # --- target (closed form) and relative geometry
    pt, vt, _at = level_turn(t, tgt[0:3], tgt[3:6], tgt[6:9], P[P_TSPEED], P[P_TOMEGA], P[P_TSTART])
    q = s[6:10] / math.sqrt(np.dot(s[6:10], s[6:10]))
    rot = quat_to_matrix(q)
    r = pt - s[0:3]
    v = vt - s[3:6]
    omega_true = los_rate(r, v)
    ds[23:26] = first_order_lag_rate(s[23:26], omega_true, P[P_TAU_S])
    vc = closing_speed(r, v)
    # --- guidance: PN command in F, then the body normal components (skid-to-turn)
    a_cmd = pn_command(P[P_NAV], vc, s[23:26], r)
    if P[P_GCOMP] > 0:
        a_cmd[1] += P[P_G]
    f_cmd = _mat_t_vec(rot, a_cmd)
    cy, cz = f_cmd[1], f_cmd[2]
    cmag = math.sqrt(cy * cy + cz * cz)
    if cmag > P[P_AMAX]:
        cy *= P[P_AMAX] / cmag
        cz *= P[P_AMAX] / cmag
    # --- air data
    rho, a_sound = _interp_air(P[P_ALT0] + s[1], air)
    vb = _mat_t_vec(rot, s[3:6])
    speed = math.sqrt(np.dot(vb, vb))
    alpha = math.atan2(-vb[1], vb[0])
    alpha_y = math.atan2(-vb[2], vb[0])
    alpha_t = math.sqrt(alpha * alpha + alpha_y * alpha_y)
    mach = speed / a_sound
    beta_m = A.supersonic_beta(max(mach, P[P_MACH_MIN]))
    qbar = 0.5 * rho * speed * speed
    # --- aerodynamics (fins: 0 top, 1 right, 2 bottom, 3 left; see flexnet_fe.flight)
    d_pitch = 0.5 * (s[14] - s[16])
    d_yaw = 0.5 * (s[15] - s[13])
    d_roll = 0.25 * (s[13] + s[14] + s[15] + s[16])
    cn_p, cm_p = A.plane_coefficients(alpha, alpha_t, d_pitch, beta_m, aero, P[P_KLIFT], P[P_KMOM], P[P_KCTRL])
    cn_y, cm_y = A.plane_coefficients(alpha_y, alpha_t, d_yaw, beta_m, aero, P[P_KLIFT], P[P_KMOM], P[P_KCTRL])
    qs = qbar * aero[A.SREF]
    qsd = qs * aero[A.DREF]
    f_b = np.empty(3)
    f_b[0] = -qs * aero[A.CA] / P[P_MASS]
    f_b[1] = qs * cn_p / P[P_MASS]
    f_b[2] = qs * cn_y / P[P_MASS]
    m_b = np.empty(3)
    m_b[0] = A.roll_moment(qbar, speed, s[10], d_roll, beta_m, aero, P[P_KLIFT], P[P_KCTRL])
    m_b[1] = -qsd * cm_y     # yaw plane: nose towards +z_b is a negative rotation about y_b
    m_b[2] = qsd * cm_p
    # --- rigid body
    ds[0:3] = s[3:6]
    ds[3:6] = _mat_vec(rot, f_b)
    ds[4] -= P[P_G]
    ds[6:10] = quat_rate(s[6:10], s[10:13])
    inertia = np.empty(3)
    inertia[0] = P[P_IXX]
    inertia[1] = P[P_IYY]
    inertia[2] = P[P_IYY]
    ds[10:13] = euler_rates(s[10:13], inertia, m_b)
    # --- autopilot: three-loop in pitch (rate ω_z) and yaw (rate −ω_y), roll-angle hold
    rate_p = s[12]
    rate_y = -s[11]
    ds[21] = P[P_WI] * (rate_p + P[P_KA] * (f_b[1] - P[P_KDC] * cy))
    ds[22] = P[P_WI] * (rate_y + P[P_KA] * (f_b[2] - P[P_KDC] * cz))
    dc_p = P[P_KR] * (s[21] + rate_p)
    dc_y = P[P_KR] * (s[22] + rate_y)
    phi = math.atan2(-rot[1, 2], rot[1, 1])
    dc_r = -(P[P_KPHI] * phi + P[P_KP] * s[10])
    # --- fin mixing and actuators
    dmax, rmax, wa, za = P[P_DMAX], P[P_RMAX], P[P_WACT], P[P_ZACT]
    for i in range(4):
        if i == 0:
            c = -dc_y + dc_r
        elif i == 1:
            c = dc_p + dc_r
        elif i == 2:
            c = dc_y + dc_r
        else:
            c = -dc_p + dc_r
        c = min(max(c, -dmax), dmax)
        rate = s[17 + i]
        acc = wa * wa * (c - s[13 + i]) - 2.0 * za * wa * rate
        if (rate >= rmax and acc > 0) or (rate <= -rmax and acc < 0):
            acc = 0.0
        pos_rate = rate
        if (s[13 + i] >= dmax and rate > 0) or (s[13 + i] <= -dmax and rate < 0):
            pos_rate = 0.0
        ds[13 + i] = pos_rate
        ds[17 + i] = acc
    # --- diagnostics
    diag[0:3] = pt
    diag[3] = cy
    diag[4] = cz
    diag[5] = f_b[1]
    diag[6] = f_b[2]
    diag[7] = alpha
    diag[8] = alpha_y
    diag[9] = mach
    diag[10] = math.sqrt(np.dot(r, r))
    diag[11] = vc
    diag[12] = dc_p
    diag[13] = dc_y
    diag[14] = dc_r
    diag[15] = phi


@njit(cache=True)
def _apply_stops(s, dmax, rmax):
    for i in range(4):
        if s[13 + i] > dmax:
            s[13 + i] = dmax
            s[17 + i] = min(s[17 + i], 0.0)
        elif s[13 + i] < -dmax:
            s[13 + i] = -dmax
            s[17 + i] = max(s[17 + i], 0.0)
        s[17 + i] = min(max(s[17 + i], -rmax), rmax)


@njit(cache=True)
def _range_rate_sign(t, s, P, tgt):
    pt, vt, _ = level_turn(t, tgt[0:3], tgt[3:6], tgt[6:9], P[P_TSPEED], P[P_TOMEGA], P[P_TSTART])
    return np.dot(pt - s[0:3], vt - s[3:6])


@njit(cache=True)
def run_engagement(s0, P, aero, air, tgt, dt, n_steps, every):
    """Advance from s0 (t = 0) with RK4 step dt [s] for at most n_steps, recording every
    ``every`` steps. Returns (times (m,), states (m, N_STATE), diags (m, N_DIAG), status,
    t_prev, s_prev, t_last, s_last) where the last two steps bracket the closest approach when
    status == STATUS_CLOSEST."""
    n_rec = n_steps // every + 2
    times = np.empty(n_rec)
    states = np.empty((n_rec, N_STATE))
    diags = np.empty((n_rec, N_DIAG))
    k1 = np.empty(N_STATE)
    k2 = np.empty(N_STATE)
    k3 = np.empty(N_STATE)
    k4 = np.empty(N_STATE)
    diag = np.empty(N_DIAG)
    s = s0.copy()
    s_prev = s0.copy()
    t = 0.0
    derivative(t, s, P, aero, air, tgt, k1, diag)
    times[0] = t
    states[0] = s
    diags[0] = diag
    m = 1
    status = STATUS_T_END
    rdot_prev = _range_rate_sign(t, s, P, tgt)
    t_prev = t
    for step in range(1, n_steps + 1):
        s_prev[:] = s
        t_prev = t
        derivative(t, s, P, aero, air, tgt, k1, diag)
        derivative(t + 0.5 * dt, s + 0.5 * dt * k1, P, aero, air, tgt, k2, diag)
        derivative(t + 0.5 * dt, s + 0.5 * dt * k2, P, aero, air, tgt, k3, diag)
        derivative(t + dt, s + dt * k3, P, aero, air, tgt, k4, diag)
        s += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        _apply_stops(s, P[P_DMAX], P[P_RMAX])
        t = step * dt
        if not np.all(np.isfinite(s)):
            status = STATUS_NONFINITE
            break
        rdot = _range_rate_sign(t, s, P, tgt)
        alt = P[P_ALT0] + s[1]
        if alt < air[0] or alt > air[0] + air[1] * (air[2] - 1):
            status = STATUS_OUT_OF_AIR_TABLE
            break
        _rho, a_sound = _interp_air(alt, air)
        if math.sqrt(np.dot(s[3:6], s[3:6])) < P[P_MACH_MIN] * a_sound:
            status = STATUS_SUBSONIC
        done = rdot_prev < 0.0 and rdot >= 0.0
        if done:
            status = STATUS_CLOSEST
        if step % every == 0 or done or status == STATUS_SUBSONIC:
            derivative(t, s, P, aero, air, tgt, k1, diag)
            times[m] = t
            states[m] = s
            diags[m] = diag
            m += 1
        if done or status == STATUS_SUBSONIC:
            break
        rdot_prev = rdot
    return times[:m], states[:m], diags[:m], status, t_prev, s_prev, t, s
