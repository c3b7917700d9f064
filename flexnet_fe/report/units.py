"""Units of run-directory keys: the one table used by the report's tables, verdict and plots.

``summary.json`` keys and ``history.csv`` columns are stored in SI and end in their unit
(``max_area_m2``, ``peak_time_s``, ``peak_von_mises_pa``, DESIGN.md §3). :func:`unit_of` maps a
key to the unit it is *shown* in: first by the whole last key segment (:data:`KEY_UNITS`, for
names whose suffix is ambiguous or absent, e.g. ``ns_per_step`` [ns] against ``impulse_ns``
[N·s]), then by the longest matching suffix (:data:`SUFFIX_UNITS`), then by the dimensionless
names (:data:`COUNT_KEYS`, :data:`RATIO_PATTERNS`). A key matched by none gets
:data:`NO_UNIT` (shown as ``?``) and is listed by :func:`unknown_units`: never guessed.

Display choices: stresses in MPa, attitude changes in mrad, times of a few ms in s (the table)
but in ms on the time axis of plots (:data:`TIME_AXIS`). Every other quantity in its SI unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Unit:
    """How a value is displayed: ``shown = value_SI * scale``, labelled ``label``."""

    label: str
    scale: float = 1.0


PA_TO_MPA = 1e-6
"""Pa → MPa."""

S_TO_MS = 1e3
"""s → ms."""

TIME_AXIS = Unit("ms", S_TO_MS)
"""Time axis of the collision / shell plots (events last a few ms)."""

DIMENSIONLESS = Unit("–")
"""A ratio or relative error (no unit)."""

COUNT = Unit("count")
"""A number of things (steps, DOFs, contacts)."""

NO_UNIT = Unit("?")
"""A key this table does not know: shown with '?' and listed as a note, never guessed."""

KEY_UNITS: dict[str, Unit] = {
    "ns_per_step": Unit("ns"),                        # wall time per step, already in ns
    "contact_stiffness": Unit("N/m^m (m = contact exponent)"),   # K_n of F = K_n δ^m, Eq. (28)
    "contact_stiffness_body": Unit("N/m^m (m = contact exponent)"),
    "contact_stiffness_fin": Unit("N/m^m (m = contact exponent)"),
    "line_stiffness_body": Unit("N/m²"),             # k_l of the line law q = k_l δ [N/m]
    "line_stiffness_fin": Unit("N/m²"),
    "static_margin_cal": Unit("calibres"),          # (x_cp − x_cg) / body diameter
    "cm_q": Unit("1/rad"),                            # pitch-damping derivative ∂C_m/∂(q d / 2V)
    "max_attitude_change_rad": Unit("mrad", 1e3),
    "cfc": Unit("CFC class (Hz)"),                    # SAE J211-1 channel frequency class
    "written": Unit("date"),
    "k_dc": DIMENSIONLESS,                            # three-loop autopilot DC gain 1 + 1/(K_a V)
    "k_phi": DIMENSIONLESS,                           # roll-angle gain, rad of fin per rad of roll
    "tolerance": DIMENSIONLESS,                       # a relative move allowed (collide.resolution_tolerance)
}
"""Whole last key segment → unit (takes precedence over suffixes)."""

# Longest suffixes first is enforced in unit_of; the order here is for reading.
SUFFIX_UNITS: dict[str, Unit] = {
    "_s_per_m": Unit("s/m"),
    "_db": Unit("dB"),
    "_kgpm3": Unit("kg/m³"),
    "_mps2": Unit("m/s²"),
    "_rps2": Unit("rad/s²"),
    "_radps": Unit("rad/s"),
    "_rps": Unit("rad/s"),
    "_mps": Unit("m/s"),
    "_kgm2": Unit("kg·m²"),
    "_pa": Unit("MPa", PA_TO_MPA),
    "_m2": Unit("m²"),
    "_m3": Unit("m³"),
    "_rad": Unit("rad"),
    "_deg": Unit("deg"),
    "_kg": Unit("kg"),
    "_hz": Unit("Hz"),
    "_rel": DIMENSIONLESS,
    "_ns": Unit("N·s"),
    "_n": Unit("N"),
    "_j": Unit("J"),
    "_w": Unit("W"),
    "_g": Unit("g (load factor)"),
    "_m": Unit("m"),
    "_s": Unit("s"),
}
"""Key suffix → unit (the stored value is SI; ``_pa`` is shown in MPa)."""

COUNT_KEYS = frozenset({"steps", "dofs", "contacts", "snapshots", "iterations", "nodes", "cells",
                        "segments", "fins", "events", "samples", "workers",
                        "rope_split"})                 # pieces per rope segment near the path
"""Last key segments that are counts."""

COUNT_SUFFIXES = ("_nodes", "_cells", "_segments", "_crossings", "_unresolved", "_steps", "_count", "_frames",
                  "_windows", "_samples")
"""Suffixes of counts (``free_nodes``, ``segment_crossings_unresolved``)."""

RATIO_PATTERNS = ("_over_", "_ratio", "_fraction", "_factor", "_scale", "damage", "effectiveness",
                  "multipliers", "_zeta", "efficiency", "remaining", "_share", "restitution")
"""Substrings of dimensionless keys (``dv_over_v``, ``peak_over_yield``, ``rotary_inertia_scale``)."""

BOOLEAN_KEYS = frozenset({"passed_through", "hit", "tunnelling", "tunnelled", "captured", "converged"})
"""Yes/no keys (no unit needed: shown as yes / no)."""


def unit_of(key: str) -> Unit:
    """Display unit of a dotted summary key or CSV column, from its last segment; when that
    segment is a name (``fin_impulse_ns.wing_1``), from the segment before it."""
    parts = key.lower().split(".")
    for k in range(len(parts) - 1, -1, -1):
        unit = _segment_unit(parts[k])
        if unit is not NO_UNIT:
            return unit
    return NO_UNIT


def _segment_unit(last: str) -> Unit:
    if last in KEY_UNITS:
        return KEY_UNITS[last]
    for suffix in sorted(SUFFIX_UNITS, key=len, reverse=True):
        if last.endswith(suffix):
            return SUFFIX_UNITS[suffix]
    if last in COUNT_KEYS or last.startswith("n_") or last.endswith(COUNT_SUFFIXES):
        return COUNT
    if any(p in last for p in RATIO_PATTERNS):
        return DIMENSIONLESS
    return NO_UNIT


def unit_label(key: str, value=None) -> str:
    """The unit text of a table row: '' for booleans, strings and missing values (they need
    none), else :func:`unit_of`'s label."""
    if value is None or isinstance(value, (bool, str)) or key.rsplit(".", 1)[-1].lower() in BOOLEAN_KEYS:
        return ""
    return unit_of(key).label


def unknown_units(keys_values: dict) -> list[str]:
    """Numeric keys of a flattened section whose unit this table does not know (a list counts as
    numeric when it holds numbers; a list of names, such as ``resolution_check.flagged``, needs none)."""
    return [k for k, v in keys_values.items() if _numeric(v) and unit_of(k) is NO_UNIT]


def _numeric(v) -> bool:
    if isinstance(v, list):
        return any(_numeric(x) for x in v)
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def format_value(value, unit: Unit = Unit("")) -> str:
    """A summary value as text: floats scaled by ``unit`` to 4 significant digits, lists as
    ``[a, b, c]``, booleans as yes/no, ``None`` (JSON null) as ``—``."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, (int, float)):
        v = value * unit.scale
        if isinstance(value, int) and unit.scale == 1.0:
            return str(value)
        return f"{v:.4g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(format_value(v, unit) for v in value) + "]"
    return str(value)


def with_unit(value, unit: Unit) -> str:
    """``format_value`` followed by the unit label (``'503 MPa'``); no label for —/yes/no."""
    text = format_value(value, unit)
    if value is None or isinstance(value, bool) or not unit.label or unit in (COUNT, NO_UNIT):
        return text
    return f"{text} {unit.label}"


PREFIXES = ((1e-9, "n"), (1e-6, "µ"), (1e-3, "m"), (1.0, ""), (1e3, "k"), (1e6, "M"), (1e9, "G"))
"""SI prefixes :func:`axis_unit` may choose."""

PREFIXABLE = frozenset({"m", "s", "N", "J", "Pa", "rad", "N·s", "W", "m/s", "rad/s"})
"""Base units that take an SI prefix on a plot axis (not m², kg/m³, m/s² — km/s² reads oddly)."""


def axis_unit(key: str, peak_abs: float) -> Unit:
    """Unit for a plot axis of ``key`` whose largest magnitude is ``peak_abs`` (SI): the SI
    base unit with the prefix that puts the peak in [1, 1000) (so an attitude of 3e-5 rad is
    drawn in µrad, not 'rad × 1e-5'). Stresses keep MPa; keys without a prefixable unit keep
    :func:`unit_of`."""
    unit = unit_of(key)
    base = "Pa" if unit.label == "MPa" else unit.label
    if base == "mrad":
        base = "rad"
    if base not in PREFIXABLE or base == "Pa" or not math.isfinite(peak_abs) or peak_abs <= 0:
        return unit
    for factor, prefix in reversed(PREFIXES):
        if peak_abs >= factor:
            return Unit(prefix + base, 1.0 / factor)
    return Unit("n" + base, 1e9)


def plain_log_axis(axis) -> None:
    """Log-scale tick labels as plain numbers (0.01, 0.1, 1, 10; '4×10⁰' never appears) and no
    labels on the minor ticks. ``axis``: a matplotlib ``ax.xaxis`` / ``ax.yaxis``."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    axis.set_major_locator(LogLocator(base=10.0))
    axis.set_major_formatter(FuncFormatter(lambda v, _pos: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())
