"""Read a run directory (the DESIGN.md §3 contract) into plain data for the report.

Nothing here computes physics or invents numbers: every figure comes from ``summary.json``,
``status.json``, ``resolved.json`` or a stage's own files; what is missing is recorded as a note
and shown as missing.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flexnet_fe.errors import FlexnetError
from flexnet_fe.runs import RESOLVED, STATUS, SUMMARY

STAGES = ("deploy", "collide", "shell", "flight")
"""Pipeline stages in the order they run (``flexnet_fe.config.Stage``)."""

STATES = ("pending", "running", "done", "failed", "interrupted", "stale")
"""The states ``status.json`` may hold (``flexnet_fe.runs.STATES``); anything else is reported as unknown."""

FIN_PEAK_KEY = "peak_von_mises_pa"
"""A shell-summary entry that is a dict with this key is one fin's result."""


@dataclass(frozen=True)
class StageInfo:
    """One stage as the run directory records it.

    state       status.json state, or ``"unknown"`` when status.json is missing or unreadable
    requested   whether the resolved case lists the stage (``None``: resolved.json missing)
    error       the error recorded in status.json for a failed stage
    wall_s      wall time recorded in status.json [s]
    section     the stage's section of summary.json (``None`` when absent)
    folder      ``run_dir/<stage>`` when it exists
    """

    name: str
    state: str
    requested: bool | None
    error: str | None
    wall_s: float | None
    section: dict | None
    folder: Path | None

    @property
    def complete(self) -> bool:
        """Done per status.json AND has its summary section: the only case shown as complete."""
        return self.state == "done" and self.section is not None


@dataclass(frozen=True)
class RunData:
    """What the report shows about one run directory."""

    run_dir: Path
    resolved: dict | None
    status: dict | None
    summary: dict | None
    stages: tuple[StageInfo, ...]
    notes: tuple[str, ...] = field(default=())
    """problems found while reading (missing or unreadable files, inconsistencies)"""

    @property
    def case(self) -> dict:
        """The resolved case (``{}`` when resolved.json is missing)."""
        return (self.resolved or {}).get("case", {}) or {}

    def stage(self, name: str) -> StageInfo:
        return next(s for s in self.stages if s.name == name)


def _read_json(path: Path, notes: list[str]) -> dict | None:
    if not path.is_file():
        notes.append(f"{path.name} is missing")
        return None
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError) as err:
        notes.append(f"{path.name} is unreadable ({err})")
        return None
    if not isinstance(data, dict):
        notes.append(f"{path.name} does not hold a JSON object")
        return None
    return data


def read_run(run_dir: Path) -> RunData:
    """Read ``resolved.json``, ``status.json``, ``summary.json`` and the stage folders.

    Raises :class:`FlexnetError` if ``run_dir`` holds none of the three JSON files (it is not a
    run directory). A stage is listed when the case requests it, status.json names it, the
    summary has its section or its folder exists.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise FlexnetError(f"{run_dir}: no such run directory")
    notes: list[str] = []
    resolved = _read_json(run_dir / RESOLVED, notes)
    status = _read_json(run_dir / STATUS, notes)
    summary = _read_json(run_dir / SUMMARY, notes)
    if resolved is None and status is None and summary is None:
        raise FlexnetError(f"{run_dir}: not a run directory (no resolved.json, status.json or summary.json)")

    case = (resolved or {}).get("case") or {}
    requested = set(((case.get("case") or {}).get("stages")) or [])
    st_stages = (status or {}).get("stages") or {}
    summ = summary or {}
    names = [s for s in STAGES if s in requested or s in st_stages or s in summ or (run_dir / s).is_dir()]
    names += sorted(s for s in set(st_stages) | set(summ) if s not in STAGES)
    if status is not None and resolved is not None and status.get("case_hash") not in (None, resolved.get("case_hash")):
        notes.append("status.json and resolved.json have different case hashes: the stage states may "
                     "belong to another version of the case")

    stages = []
    for name in names:
        entry = st_stages.get(name)
        if status is None:
            state = "unknown"
        elif entry is None:
            state = "unknown"
            notes.append(f"status.json has no entry for stage '{name}'")
        else:
            state = str(entry.get("state", "unknown"))
            if state not in STATES:
                notes.append(f"status.json: stage '{name}' has unknown state '{state}'")
                state = "unknown"
        section = summ.get(name)
        if section is not None and not isinstance(section, dict):
            notes.append(f"summary.json: section '{name}' is not an object")
            section = None
        if state == "done" and section is None:
            notes.append(f"stage '{name}' is done in status.json but summary.json has no '{name}' section")
        if section is not None and state != "done":
            notes.append(f"summary.json has a '{name}' section but status.json says '{state}': "
                         "its numbers are not shown")
        folder = run_dir / name
        wall = (entry or {}).get("wall_s")
        stages.append(StageInfo(
            name=name, state=state, requested=(name in requested) if resolved is not None else None,
            error=(entry or {}).get("error"), wall_s=float(wall) if isinstance(wall, (int, float)) else None,
            section=section, folder=folder if folder.is_dir() else None))
    return RunData(run_dir=run_dir, resolved=resolved, status=status, summary=summary,
                   stages=tuple(stages), notes=tuple(notes))


def flatten(section: dict, prefix: str = "") -> dict[str, Any]:
    """Nested dict → ``{"a.b": value}``; lists and scalars are kept as values."""
    out: dict[str, Any] = {}
    for k, v in section.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def fin_results(shell_section: dict) -> dict[str, dict]:
    """The per-fin entries of the shell summary: ``{fin name: {peak_von_mises_pa: ...}}``."""
    return {k: v for k, v in shell_section.items() if isinstance(v, dict) and FIN_PEAK_KEY in v}


def stage_pngs(run_dir: Path, folder: Path) -> list[Path]:
    """Every PNG below a stage folder (sorted), as paths relative to ``run_dir``."""
    return sorted(p.relative_to(run_dir) for p in folder.rglob("*.png") if p.is_file())


def yield_strength(case: dict) -> tuple[float | None, str]:
    """Fin yield strength [Pa] from ``case.missile.material.yield_strength`` and the material
    name; ``(None, reason)`` when the resolved case does not hold it."""
    missile = case.get("missile")
    if not isinstance(missile, dict):
        return None, "the resolved case has no [missile] table"
    material = missile.get("material")
    if not isinstance(material, dict) or not isinstance(material.get("yield_strength"), (int, float)):
        return None, "the resolved case has no missile.material.yield_strength"
    return float(material["yield_strength"]), str(material.get("name", "fin material"))
