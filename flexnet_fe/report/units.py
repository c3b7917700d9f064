"""Units of run-directory keys, read from their suffix (DESIGN.md §3: names carry their unit).

``summary.json`` keys and ``history.csv`` columns end in their SI unit (``max_area_m2``,
``peak_time_s``, ``peak_von_mises_pa``). The report shows them in the unit named here; a key
whose suffix is not in :data:`SUFFIX_UNITS` is shown as it is with no unit (never guessed).
Stresses are shown in MPa; every other quantity in its SI unit.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Unit:
    """How a value is displayed: ``shown = value * scale``, labelled ``label``."""

    label: str
    scale: float = 1.0


PA_TO_MPA = 1e-6
"""Pa → MPa."""

# Longest suffixes first so that ``_m2`` wins over ``_m`` and ``_mps2`` over ``_s``.
SUFFIX_UNITS: dict[str, Unit] = {
    "_kgpm3": Unit("kg/m³"),
    "_mps2": Unit("m/s²"),
    "_radps": Unit("rad/s"),
    "_mps": Unit("m/s"),
    "_kgm2": Unit("kg·m²"),
    "_pa": Unit("MPa", PA_TO_MPA),
    "_m2": Unit("m²"),
    "_m3": Unit("m³"),
    "_rad": Unit("rad"),
    "_deg": Unit("deg"),
    "_kg": Unit("kg"),
    "_hz": Unit("Hz"),
    "_rel": Unit("– (relative)"),
    "_n": Unit("N"),
    "_j": Unit("J"),
    "_w": Unit("W"),
    "_g": Unit("g (load factor)"),
    "_m": Unit("m"),
    "_s": Unit("s"),
}

NO_UNIT = Unit("")


def unit_of(key: str) -> Unit:
    """Display unit of a dotted summary key or CSV column from its last segment's suffix."""
    last = key.rsplit(".", 1)[-1].lower()
    for suffix in sorted(SUFFIX_UNITS, key=len, reverse=True):
        if last.endswith(suffix):
            return SUFFIX_UNITS[suffix]
    return NO_UNIT


def format_value(value, unit: Unit = NO_UNIT) -> str:
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
