"""Collision numbers that are defined: the SAE J211-1 CFC filter and window-free metrics (issue 9 §5).

A raw peak of the missile acceleration over one output interval Δ is the largest impulse that
falls in one interval divided by mΔ: halve Δ and a rope strike that lasts less than Δ doubles it.
Crash engineers read impact accelerations through a channel-frequency-class (CFC) filter instead:

- :func:`cfc_filter` is the SAE J211-1 (rev. 2007; ISO 6487 gives the same filter) phaseless
  4-pole Butterworth low pass, realised as the standard's 2-pole recursion run forward and then
  backward. Its output is the band-limited acceleration: a rope strike shorter than Δ enters as
  its impulse J (the interval mean is J/(mΔ) over a width Δ) and leaves as J/m times the filter's
  impulse response, which does not depend on Δ (to O((2π F_N Δ)²), see the tests). So the filtered
  peak is a property of the impact, and the raw one is a property of the output interval.
- :func:`collision_metrics` collects the window-free numbers from the collide histories: missile
  Δv and impulse (total, world and body axes), Δv/v, the impulse on each fin, the contact
  duration, and the CFC-filtered peak acceleration (magnitude, per body axis, time). The raw
  one-interval peak is kept only under the key ``peak_accel_raw_mps2`` with its window.

Only numpy and scipy are used (plus the project's error type), so this module does not depend on
the state of the collision kernel. Series conventions (those of ``collide/history.csv``): row k
of a history is the state at t_k; an *interval series* (accelerations, contact force) holds in
row k ≥ 1 the mean over (t_{k-1}, t_k] and row 0 is ignored.

Default class :data:`DEFAULT_CFC` = 180, justified in :data:`DEFAULT_CFC_REASON` and in
docs/validation.md, "Collision metrics: CFC filter (issue 9 §5)".
"""

from __future__ import annotations

import math
from typing import NamedTuple, Sequence

import numpy as np
from scipy import signal

from flexnet_fe.errors import FlexnetError

#: The channel frequency classes of SAE J211-1 Table 1 / ISO 6487; :func:`cfc_filter` accepts any
#: positive class, these are the ones the standard names.
CFC_CLASSES = (60, 180, 600, 1000)

#: J211-1 (2007) Appendix C: design frequency of each 2-pole pass, ω_d = 2π · CFC · 2.0775.
#: 2.0775 = (5/3) / (√2 − 1)^(1/4): with each pass |H₂|² = 1/(1 + (f/f_d)⁴), the forward-backward
#: product |H₂|² is −3 dB where (f/f_d)⁴ = √2 − 1, i.e. at f = 0.80224 f_d = (5/3) CFC: the
#: standard's "3 dB limit frequencies" 100 / 300 / 1000 / 1650 Hz of CFC 60 / 180 / 600 / 1000
#: (1650 is 1666.7 rounded; the filter is −2.91 dB there). At f_d itself the 4-pole gain is −6 dB.
DESIGN_FACTOR = 2.0775

#: −3 dB frequency of the phaseless filter over the class, F_N / CFC (J211-1: F_N ≈ 5/3 · CFC).
F3DB_FACTOR = 5.0 / 3.0

#: J211-1 Appendix C / ISO 6487 list a minimum sampling frequency of 10 × CFC for each class
#: (600 Hz for CFC 60 ... 10 kHz for CFC 1000); below it the bilinear warping moves the −3 dB point
#: by more than the corridor allows. :func:`cfc_filter` refuses a coarser sampling.
MIN_SAMPLING_PER_CFC = 10.0

#: Default channel frequency class of the missile CG acceleration (see DEFAULT_CFC_REASON).
DEFAULT_CFC = 180

DEFAULT_CFC_REASON = (
    "CFC 180 (−3 dB at 300 Hz). SAE J211-1 recommends CFC 60 for whole-vehicle kinematics over "
    "a ~100 ms crash pulse, CFC 180 for structural accelerations integrated to velocity, CFC "
    "600/1000 for local component loads. The net collision lasts ~8–10 ms: CFC 180 passes the "
    "peak of a 10 ms half-sine to 0.035 % (5 ms: 0.44 %), where CFC 60 takes off 4.9 % (30 %). "
    "Above ~300 Hz the CG acceleration is the sequence of discrete rope strikes, whose size depends "
    "on the output interval and the net discretisation: on a radar x traction history the CFC 180 "
    "peak moves 0.04 % when the window goes from 10 to 20 µs, CFC 600 1.3 %, CFC 1000 2.9 %, the raw "
    "peak 50 %. The CG acceleration loads the fins as a rigid-body inertial load; the fins' own "
    "contact forces reach the shell stage unfiltered. Sampling: the 10 µs output interval "
    "(100 kHz) is 555 × CFC 180, far above J211's minimum of 10 × CFC."
)

# Round-off level to which the padded ends must have settled (|pole|^n below this).
_SETTLE_TOL = 1e-16
# Relative deviation of the sample interval tolerated as "uniform" (t_k = k Δ in floating point
# deviates by ~1e-12 relative; a true non-uniform grid by far more).
_UNIFORM_RTOL = 1e-6
# Largest tolerated mismatch | |a_body| − |a_world − g| | / max |a| (the two should agree to O(ωΔ)).
_FRAME_CHECK_RTOL = 1e-3


class MetricsInputError(FlexnetError, ValueError):
    """Unusable input to the collision metrics: one clear line (exit code 2, like a case error)."""

    exit_code = 2


class MissileHistory(NamedTuple):
    """The missile's collide history, as ``collide/history.csv`` holds it.

    t_s              output times [s], shape (nt,), uniform interval Δ, nt ≥ 3
    vel_world_mps    CG velocity at t_k, world axes [m/s], shape (nt, 3)
    accel_body_mps2  interval series: mean non-gravitational (contact) acceleration of the CG over
                     (t_{k-1}, t_k] in body axes [m/s²], shape (nt, 3), row 0 ignored — the
                     kernel's ``accel_body_{x,y,z}_mps2`` (body-axis impulse / (m Δ))
    contact_force_n  interval series: mean total contact-force magnitude on the missile [N],
                     shape (nt,), row 0 ignored (``contact_force_mean_n``); > 0 means contact
    gravity_mps2     gravity acting on the missile during the run, world axes [m/s²], shape (3,)
                     (zeros when the case turns gravity off)
    mass_kg          missile mass [kg]
    """

    t_s: np.ndarray
    vel_world_mps: np.ndarray
    accel_body_mps2: np.ndarray
    contact_force_n: np.ndarray
    gravity_mps2: np.ndarray
    mass_kg: float


class FinContacts(NamedTuple):
    """Fin loads as ``collide/fin_contacts.npz`` holds them (only the fields the impulses need).

    fin_names   fin names, shape (n_fins,)
    fin         fin index of each contact row, shape (n_rows,) int
    force_n     mean force of each row over its output interval [N], shape (n_rows, 3)
    interval_s  the output interval Δ [s] the mean forces are taken over
    """

    fin_names: Sequence[str]
    fin: np.ndarray
    force_n: np.ndarray
    interval_s: float


def fin_contacts_from_npz(data) -> FinContacts:
    """:class:`FinContacts` from a loaded ``fin_contacts.npz`` (fields ``fin_names, t, fin, force``);
    Δ is the spacing of its interval midpoints ``t`` [s]."""
    t = np.asarray(data["t"], dtype=float)
    if t.size < 2:
        raise MetricsInputError(f"fin_contacts.npz: t: {t.size} interval(s); need ≥ 2 to know the interval")
    return FinContacts([str(n) for n in data["fin_names"]], np.asarray(data["fin"]),
                       np.asarray(data["force"], dtype=float).reshape(-1, 3), sample_interval(t, "fin_contacts.t"))


# -- the CFC filter ------------------------------------------------------------------------------


def sample_interval(t, name: str = "t") -> float:
    """The uniform sample interval Δ [s] of times ``t`` [s], shape (n,), n ≥ 2; one-line error if
    the spacing is not uniform (to 1e-6 relative) or not increasing."""
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise MetricsInputError(f"collision metrics: {name}: need a 1-D series of ≥ 2 times, got shape {t.shape}")
    d = np.diff(t)
    dt = (t[-1] - t[0]) / (t.size - 1)
    if not np.isfinite(dt) or dt <= 0.0:
        raise MetricsInputError(f"collision metrics: {name}: times must increase (mean interval {dt:.3g} s)")
    dev = float(np.max(np.abs(d - dt)))
    if dev > _UNIFORM_RTOL * dt:
        raise MetricsInputError(f"collision metrics: {name}: sample interval not uniform (deviates by {dev:.3g} s "
                                f"from the mean {dt:.3g} s); the CFC filter needs a uniform interval")
    return float(dt)


def cfc_coefficients(cfc: float, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients (b, a) of one 2-pole pass, SAE J211-1 (2007) Appendix C, for sampling
    interval ``dt`` [s]. In the standard's notation, with T = dt:

        ω_d = 2π · CFC · 2.0775                                  (design frequency, rad/s)
        ω_a = sin(ω_d T/2) / cos(ω_d T/2)                        (bilinear pre-warping)
        a0 = ω_a² / (1 + √2 ω_a + ω_a²),  a1 = 2 a0,  a2 = a0
        b1 = −2 (ω_a² − 1) / (1 + √2 ω_a + ω_a²)
        b2 = (−1 + √2 ω_a − ω_a²) / (1 + √2 ω_a + ω_a²)
        Y(t) = a0 X(t) + a1 X(t−1) + a2 X(t−2) + b1 Y(t−1) + b2 Y(t−2)

    returned in scipy's convention y[n] = Σ b_i x[n−i] − Σ_{i≥1} a_i y[n−i]: b = (a0, a1, a2),
    a = (1, −b1, −b2). This is scipy.signal.butter(2, 2.0775·CFC, fs=1/dt) to round-off (a test
    checks it); it is written out so the code reads as the standard.
    """
    wd = 2.0 * math.pi * cfc * DESIGN_FACTOR
    wa = math.sin(wd * dt / 2.0) / math.cos(wd * dt / 2.0)
    den = 1.0 + math.sqrt(2.0) * wa + wa * wa
    a0 = wa * wa / den
    b1 = -2.0 * (wa * wa - 1.0) / den
    b2 = (-1.0 + math.sqrt(2.0) * wa - wa * wa) / den
    return np.array([a0, 2.0 * a0, a0]), np.array([1.0, -b1, -b2])


def cfc_gain(f, cfc: float, dt: float):
    """Closed-form gain (linear, no phase) of the phaseless filter at frequency ``f`` [Hz]:
    |H(f)| = |H₂|² = 1 / (1 + (tan(π f T) / tan(π f_d T))⁴), f_d = 2.0775 · CFC, T = dt — the
    bilinear image of the analogue 2-pole Butterworth, squared by the forward-backward run."""
    r = np.tan(np.pi * np.asarray(f, dtype=float) * dt) / math.tan(math.pi * DESIGN_FACTOR * cfc * dt)
    return 1.0 / (1.0 + r ** 4)


def _check_cfc(cfc, dt: float) -> float:
    try:
        cfc = float(cfc)
    except (TypeError, ValueError):
        raise MetricsInputError(f"collision metrics: cfc: {cfc!r} is not a number") from None
    if not (math.isfinite(cfc) and cfc > 0.0):
        raise MetricsInputError(f"collision metrics: cfc: must be a positive class (e.g. {CFC_CLASSES}), got {cfc}")
    fs = 1.0 / dt
    if fs < MIN_SAMPLING_PER_CFC * cfc:
        raise MetricsInputError(
            f"collision metrics: CFC {cfc:g} needs a sampling rate ≥ {MIN_SAMPLING_PER_CFC:g} × CFC = "
            f"{MIN_SAMPLING_PER_CFC * cfc:.4g} Hz (SAE J211-1 / ISO 6487); the interval {dt:.3g} s gives "
            f"{fs:.4g} Hz: lower the output interval or the class")
    return cfc


def settle_samples(cfc: float, dt: float) -> int:
    """Samples after which a 2-pole pass's free response has decayed to round-off (|pole|ⁿ ≤ 1e-16):
    the length of the padding in :func:`cfc_filter`."""
    _, a = cfc_coefficients(cfc, dt)
    r = float(np.max(np.abs(np.roots(a))))
    return int(math.ceil(math.log(_SETTLE_TOL) / math.log(r) * 1.1)) + 2


def cfc_filter(t, x, cfc: float) -> np.ndarray:
    """SAE J211-1 channel-frequency-class filter of samples ``x`` taken at times ``t`` [s].

    t    (n,) uniform times [s] (one-line error otherwise); the sampling rate 1/Δ must be
         ≥ 10 × CFC (J211-1's minimum; one-line error otherwise)
    x    (n,) or (n, m) samples in any unit; each column filtered along time
    cfc  channel frequency class (60, 180, 600, 1000 in J211-1; any positive value accepted)
    returns the filtered samples, same shape and unit as ``x``

    Phaseless 4-pole Butterworth: the 2-pole recursion of :func:`cfc_coefficients` (J211-1
    Appendix C) run forward, then backward over the result (scipy.signal.filtfilt). Gain
    :func:`cfc_gain`: 1 at DC, −3 dB at (5/3)·CFC, −6 dB at 2.0775·CFC, zero phase.

    Ends. J211-1 asks for data before and after the event so that the filter's start-up
    transients fall outside it. Here each end is extended by its own value held constant for
    :func:`settle_samples` samples (the free response decays to 1e-16 within them) and each pass
    starts in the steady state of its first value (scipy's lfilter_zi), then the padding is cut
    off. For the missile acceleration, which is exactly zero before the first and after the last
    contact, this *is* the pre- and post-event data the standard asks for: the output equals the
    filter applied to an infinitely long record. (Mirror or odd padding, scipy's default, would
    invent a reflected pulse at an end that is still in contact; the held value does not invent
    an impulse when the end is at rest, and is at least a neutral continuation when it is not.)
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    dt = sample_interval(t)
    if x.shape[0] != t.size or x.ndim not in (1, 2):
        raise MetricsInputError(f"collision metrics: samples of shape {x.shape} do not match {t.size} times")
    if not np.all(np.isfinite(x)):
        raise MetricsInputError("collision metrics: the series to filter holds NaN or inf")
    cfc = _check_cfc(cfc, dt)
    b, a = cfc_coefficients(cfc, dt)
    n_pad = settle_samples(cfc, dt)
    pad = ((n_pad, n_pad),) + ((0, 0),) * (x.ndim - 1)
    xp = np.pad(x, pad, mode="edge")
    y = signal.filtfilt(b, a, xp, axis=0, padtype=None)  # steady-state start at both passes
    return y[n_pad:n_pad + t.size]


# -- window-free collision metrics ---------------------------------------------------------------


def _interval_rows(h: MissileHistory) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """(interval midpoints [s] (nt−1,), Δ [s], world specific-force accel [m/s²] (nt−1, 3),
    body accel [m/s²] (nt−1, 3)) with the inputs' shapes checked."""
    t = np.asarray(h.t_s, dtype=float)
    dt = sample_interval(t, "t_s")
    nt = t.size
    if nt < 3:
        raise MetricsInputError(f"collision metrics: t_s: {nt} output times; need ≥ 3")
    for name, arr, shape in (("vel_world_mps", h.vel_world_mps, (nt, 3)), ("accel_body_mps2", h.accel_body_mps2, (nt, 3)),
                             ("contact_force_n", h.contact_force_n, (nt,)), ("gravity_mps2", h.gravity_mps2, (3,))):
        a = np.asarray(arr, dtype=float)
        if a.shape != shape:
            raise MetricsInputError(f"collision metrics: {name}: shape {a.shape}, expected {shape}")
        if not np.all(np.isfinite(a)):
            raise MetricsInputError(f"collision metrics: {name}: holds NaN or inf")
    if not (math.isfinite(float(h.mass_kg)) and float(h.mass_kg) > 0.0):
        raise MetricsInputError(f"collision metrics: mass_kg: must be positive, got {h.mass_kg}")
    v = np.asarray(h.vel_world_mps, dtype=float)
    a_world = np.diff(v, axis=0) / dt - np.asarray(h.gravity_mps2, dtype=float)
    a_body = np.asarray(h.accel_body_mps2, dtype=float)[1:]
    return t[1:] - 0.5 * dt, dt, a_world, a_body


def _check_frames(a_world: np.ndarray, a_body: np.ndarray) -> None:
    """|a_body| must equal |Δv_world/Δ − g| interval by interval (a rotation keeps lengths; the
    interval mean of a rotating vector differs by O(ωΔ)). Catches gravity left in, a shifted row
    or a velocity from another run, each of which would silently skew the metrics."""
    mw, mb = np.linalg.norm(a_world, axis=1), np.linalg.norm(a_body, axis=1)
    scale = max(float(mw.max()), float(mb.max()), 1e-300)
    err = float(np.max(np.abs(mw - mb))) / scale
    if err > _FRAME_CHECK_RTOL:
        k = int(np.argmax(np.abs(mw - mb)))
        raise MetricsInputError(
            f"collision metrics: accel_body_mps2 and vel_world_mps disagree: |a_body| = {mb[k]:.6g} but "
            f"|Δv/Δ − g| = {mw[k]:.6g} m/s² in interval {k + 1} ({err:.2g} of the peak > {_FRAME_CHECK_RTOL:g}); "
            f"wrong gravity, a shifted row, or histories of different runs")


def contact_window(t, force, threshold: float = 0.0) -> tuple[float, float, float]:
    """(start [s], end [s], duration [s]) of contact from an interval series ``force`` [N], shape
    (nt,) (row k = mean over (t_{k-1}, t_k], row 0 ignored) at times ``t`` [s], shape (nt,): from
    the start of the first interval with force > ``threshold`` to the end of the last. The true
    duration lies within one interval below this (the first and last intervals are only partly
    in contact). (0, 0, 0) without contact."""
    t = np.asarray(t, dtype=float)
    rows = np.flatnonzero(np.asarray(force, dtype=float)[1:] > threshold) + 1
    if rows.size == 0:
        return 0.0, 0.0, 0.0
    start, end = float(t[rows[0] - 1]), float(t[rows[-1]])
    return start, end, end - start


def fin_impulses(fins: FinContacts) -> dict[str, np.ndarray]:
    """Total impulse vector [N s], shape (3,), of each fin name: Σ force · Δ over its rows (the
    frame of ``force_n``). A fin without rows gets zeros."""
    fin = np.asarray(fins.fin, dtype=np.int64)
    force = np.asarray(fins.force_n, dtype=float).reshape(-1, 3)
    if fin.shape[0] != force.shape[0]:
        raise MetricsInputError(f"fin_contacts: fin has {fin.shape[0]} rows, force {force.shape[0]}")
    n = len(fins.fin_names)
    if fin.size and (fin.min() < 0 or fin.max() >= n):
        raise MetricsInputError(f"fin_contacts: fin index outside 0..{n - 1}")
    if not np.all(np.isfinite(force)):
        raise MetricsInputError("fin_contacts: force holds NaN or inf")
    tot = np.zeros((n, 3))
    np.add.at(tot, fin, force * float(fins.interval_s))
    return {str(name): tot[i] for i, name in enumerate(fins.fin_names)}


ALTERNATION_SHARE = 0.1
"""[-] A sample alternates when its load's second difference (F_{k−1} − 2 F_k + F_{k+1}) / 4 exceeds
this share of the local mean (F_{k−1} + 2 F_k + F_{k+1}) / 4 and points against the previous
sample's (:func:`load_alternation_runs`)."""

ALTERNATION_RUN_LIMIT = 8
"""[samples] A fin load that alternates for more consecutive samples than this is flagged: a
physical strike rises over 1–4 µs (3–13 samples of 0.3125 µs) and alternates for at most a
sample or two (the three paper cases' 24 fins: ≤ 2 with the contact damping's cap); an explicit
step past its stability limit alternates for as long as it stays past it (before the cap:
infrared × traction's rudders 1–4 for 170–2 091 samples, radar × traction's rudders 2 and 4 for
15 and 23; docs/validation.md, "Contact damping at the explicit limit")."""


def load_alternation_runs(row_start, fin, force, n_fins: int) -> np.ndarray:
    """Longest run of consecutive samples in which each fin's resultant load alternates from one
    sample to the next (the signature of an explicit step past its stability limit), shape
    (n_fins,) int.

    row_start (nt + 1,) int offsets of each sample's rows, fin (ne,) int fin index of each row,
    force (ne, 3) [N] its mean force over the sample (``fin_contacts.npz``)."""
    row_start = np.asarray(row_start, dtype=np.int64)
    nt = row_start.size - 1
    out = np.zeros(n_fins, dtype=np.int64)
    if nt < 4:
        return out
    sample = np.repeat(np.arange(nt), np.diff(row_start))
    load = np.zeros((n_fins, nt, 3))
    np.add.at(load, (np.asarray(fin, dtype=np.int64), sample), np.asarray(force, dtype=float).reshape(-1, 3))
    second = load[:, :-2] - 2.0 * load[:, 1:-1] + load[:, 2:]
    mean = load[:, :-2] + 2.0 * load[:, 1:-1] + load[:, 2:]
    flip = np.einsum("fkc,fkc->fk", second[:, 1:], second[:, :-1]) < 0.0
    big = np.linalg.norm(second[:, 1:], axis=2) > ALTERNATION_SHARE * np.linalg.norm(mean[:, 1:], axis=2)
    for f, on in enumerate(flip & big):
        edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(np.int8), [0]])))
        if edges.size:
            out[f] = int((edges[1::2] - edges[::2]).max())
    return out


def filtered_peak(t_mid, accel, cfc: float) -> dict:
    """CFC-filtered peak of an acceleration interval series.

    t_mid  (n,) interval midpoints [s], uniform;  accel (n, 3) interval-mean acceleration [m/s²]
    returns {peak_accel_mps2 (|a_f| max), peak_accel_axis_mps2 ([max |a_f,i|] per column),
    peak_accel_time_s (time of the |a_f| max), filter_dv_loss_rel}: the filter acts on each column
    (J211: filter the channels, then form the resultant). ``filter_dv_loss_rel`` is
    |Σ a_f Δ − Σ a Δ| / |Σ a Δ| over the record: the share of Δv the filter spreads beyond the
    record's ends (the filter's DC gain is 1, so it is round-off when the record starts and ends
    far enough, ~ :func:`settle_samples`, from the contact).
    """
    a_f = cfc_filter(t_mid, accel, cfc)
    mag = np.linalg.norm(a_f, axis=1)
    k = int(np.argmax(mag))
    dv = np.asarray(accel, dtype=float).sum(axis=0)
    dv_f = a_f.sum(axis=0)
    norm = float(np.linalg.norm(dv))
    return {
        "peak_accel_mps2": float(mag[k]),
        "peak_accel_axis_mps2": [float(v) for v in np.max(np.abs(a_f), axis=0)],
        "peak_accel_time_s": float(np.asarray(t_mid, dtype=float)[k]),
        "filter_dv_loss_rel": float(np.linalg.norm(dv_f - dv)) / norm if norm > 0.0 else 0.0,
    }


def collision_metrics(missile: MissileHistory, fins: FinContacts, *, cfc: float = DEFAULT_CFC) -> dict:
    """The window-free collision numbers and the CFC-filtered peak acceleration (issue 9 §5).

    missile  :class:`MissileHistory` (times, world velocity, body acceleration, contact force,
             gravity, mass);  fins :class:`FinContacts`;  cfc the channel frequency class
    returns a JSON-ready dict (SI units):

    cfc                     the class used
    peak_accel_mps2         max |a_f|, a_f the CFC-filtered body-axis CG acceleration (contact only)
    peak_accel_axis_mps2    [max |a_f,x|, max |a_f,y|, max |a_f,z|], body axes
    peak_accel_time_s       time of peak_accel_mps2 (interval midpoints)
    peak_accel_raw_mps2     RAW: max over intervals of the interval-mean |a|; depends on the window
    raw_window_s            the window of the raw peak (the output interval Δ)
    delta_v_world_mps       Δv from the collision in world axes: v(t_end) − v(t_0) − g (t_end − t_0)
    delta_v_mps             |delta_v_world_mps|
    delta_v_axis_mps        body-axis Δv: Σ a_body Δ (what an accelerometer at the CG integrates)
    dv_over_v               |Δv| / |v(t_0)|
    impulse_world_ns        m · delta_v_world_mps (non-gravitational impulse on the missile)
    impulse_ns              |impulse_world_ns|
    fin_impulse_ns          {fin name: |Σ F Δ|}, fin_impulse_vector_ns {fin name: Σ F Δ (3,)}
    contact_start_s, contact_end_s, contact_duration_s   from the contact-force series
    filter_dv_loss_rel      share of Δv the filter spreads beyond the record ends (see filtered_peak)
    warnings                one line each: contact still on at a record end (the filtered values
                            within the filter's settling time of that end are then not defined)
    """
    t_mid, dt, a_world, a_body = _interval_rows(missile)
    _check_frames(a_world, a_body)
    t = np.asarray(missile.t_s, dtype=float)
    v = np.asarray(missile.vel_world_mps, dtype=float)
    dv_world = v[-1] - v[0] - np.asarray(missile.gravity_mps2, dtype=float) * (t[-1] - t[0])  # = Σ a_world Δ
    dv_body = a_body.sum(axis=0) * dt
    speed0 = float(np.linalg.norm(v[0]))
    peak = filtered_peak(t_mid, a_body, cfc)
    start, end, duration = contact_window(t, missile.contact_force_n)
    imp = fin_impulses(fins)
    force = np.asarray(missile.contact_force_n, dtype=float)
    warnings = []
    for where, val in (("first", force[1]), ("last", force[-1])):
        if val > 0.0:
            warnings.append(f"collide: contact force {val:.3g} N in the {where} output interval: the CFC {cfc:g} "
                            f"filtered acceleration within {settle_samples(float(cfc), dt) * dt * 1e3:.3g} ms of "
                            f"that end assumes the force continues; run longer")
    out = {
        "cfc": float(cfc),
        "peak_accel_mps2": peak["peak_accel_mps2"],
        "peak_accel_axis_mps2": peak["peak_accel_axis_mps2"],
        "peak_accel_time_s": peak["peak_accel_time_s"],
        "peak_accel_raw_mps2": float(np.linalg.norm(a_body, axis=1).max()),
        "raw_window_s": dt,
        "delta_v_world_mps": [float(c) for c in dv_world],
        "delta_v_mps": float(np.linalg.norm(dv_world)),
        "delta_v_axis_mps": [float(c) for c in dv_body],
        "dv_over_v": float(np.linalg.norm(dv_world)) / speed0 if speed0 > 0.0 else None,
        "impulse_world_ns": [float(c) * float(missile.mass_kg) for c in dv_world],
        "impulse_ns": float(np.linalg.norm(dv_world)) * float(missile.mass_kg),
        "fin_impulse_ns": {k: float(np.linalg.norm(j)) for k, j in imp.items()},
        "fin_impulse_vector_ns": {k: [float(c) for c in j] for k, j in imp.items()},
        "contact_start_s": start,
        "contact_end_s": end,
        "contact_duration_s": duration,
        "filter_dv_loss_rel": peak["filter_dv_loss_rel"],
        "warnings": warnings,
    }
    return out
