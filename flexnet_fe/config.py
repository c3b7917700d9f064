"""Case files: ``cases/<name>/case.toml`` → a validated, frozen :class:`Case` (SI units).

Every table of the case file is a :class:`~flexnet_fe.schema.Section` owned by the module that
uses it; this module only composes them and turns any problem into one :class:`CaseError` line
naming the file, the dotted field path and the reason. Nothing in a case file is executed.
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from enum import Enum
from pathlib import Path
from typing import Any

from pydantic import Field, ValidationError, model_validator

from flexnet_fe.errors import CaseError
from flexnet_fe.schema import Section
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.flight.config import FlightConfig
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.net.config import DeployConfig, NetConfig
from flexnet_fe.shell.config import ShellConfig


class Stage(str, Enum):
    """The pipeline's stages, in the order they run."""

    deploy = "deploy"
    collide = "collide"
    shell = "shell"
    flight = "flight"


STAGE_ORDER = tuple(Stage)

# The tables each stage needs (besides [case], [atmosphere] and [deploy], which have defaults).
STAGE_SECTIONS: dict[Stage, tuple[str, ...]] = {
    Stage.deploy: ("net",),
    Stage.collide: ("net", "missile", "collide"),
    Stage.shell: ("missile", "collide", "shell"),
    Stage.flight: ("flight",),
}


class CaseMeta(Section):
    """The ``[case]`` table."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$",
                      description="case name; the default run directory is runs/<name>")
    description: str = Field("", description="free text shown in reports")
    stages: tuple[Stage, ...] = Field(min_length=1, description="stages `flexnet run` runs, in pipeline order")


class AtmosphereConfig(Section):
    """The ``[atmosphere]`` table: ISA (ISO 2533) via the ``ambiance`` library."""

    altitude: float = Field(8000.0, ge=-5000.0, le=80000.0,
                            description="geometric altitude of the scene [m] (paper §V-A: 8 km)")


class Case(Section):
    """A whole case file. Tables a case's stages do not need may be left out."""

    case: CaseMeta
    atmosphere: AtmosphereConfig = AtmosphereConfig()
    net: NetConfig | None = None
    deploy: DeployConfig = DeployConfig()
    missile: MissileConfig | None = None
    collide: CollideConfig | None = None
    shell: ShellConfig | None = None
    flight: FlightConfig | None = None

    @model_validator(mode="after")
    def _stages_have_their_tables(self) -> "Case":
        for stage in self.case.stages:
            for table in STAGE_SECTIONS[stage]:
                if getattr(self, table) is None:
                    raise ValueError(f"stage '{stage.value}' needs a [{table}] table")
        return self


def _dotted(loc: tuple[Any, ...], data: Any) -> str:
    """Dotted field path from a pydantic error location. Walks the raw data alongside, so the
    tag pydantic inserts for a discriminated union (e.g. ``net.traction.x``) is dropped."""
    parts: list[str] = []
    node = data
    for item in loc:
        if isinstance(node, dict) and node.get("kind") == item and item not in node:
            continue  # union tag, not a key of the file
        parts.append(f"[{item}]" if isinstance(item, int) else str(item))
        try:
            node = node[item]
        except (KeyError, IndexError, TypeError):
            node = None
    return ".".join(parts).replace(".[", "[")


def format_validation_error(err: ValidationError, data: Any) -> tuple[str, str]:
    """(field path, reason) of the first error, with a count of the others."""
    errors = err.errors(include_url=False)
    first = errors[0]
    field = _dotted(tuple(first["loc"]), data) or "(top level)"
    reason = first["msg"]
    if first["type"] == "extra_forbidden":
        reason = "unknown key"
    elif "input" in first and first["type"] not in ("missing",) and not isinstance(first["input"], dict):
        reason += f" (got {first['input']!r})"
    if len(errors) > 1:
        reason += f" (+{len(errors) - 1} more error{'s' if len(errors) > 2 else ''})"
    return field, reason


def parse_override(text: str) -> tuple[list[str], Any]:
    """``--set a.b.c=VALUE`` → (["a", "b", "c"], value). VALUE is read as a TOML value
    (``1e-3``, ``true``, ``"radar"``, ``[1, 2]``); a bare word that is not TOML is taken as a string."""
    if "=" not in text:
        raise CaseError("--set", text, "expected key=value")
    key, raw = text.split("=", 1)
    path = [p for p in key.strip().split(".") if p]
    if not path:
        raise CaseError("--set", text, "empty key")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return path, value


def apply_overrides(data: dict, overrides: list[str]) -> dict:
    """Return a copy of the raw case dict with ``--set`` overrides applied."""
    data = json.loads(json.dumps(data))
    for text in overrides:
        path, value = parse_override(text)
        node = data
        for key in path[:-1]:
            node = node.setdefault(key, {})
            if not isinstance(node, dict):
                raise CaseError("--set", ".".join(path), f"'{key}' is not a table")
        node[path[-1]] = value
    return data


def case_file(path: Path) -> Path:
    """A case directory or its case.toml → the case.toml path."""
    path = Path(path)
    return path / "case.toml" if path.is_dir() else path


def load_case(path: Path, overrides: list[str] | None = None) -> tuple[Case, Path]:
    """Read and validate a case. Returns (case, case directory). Raises CaseError."""
    file = case_file(path)
    if not file.is_file():
        raise CaseError(file, "", "no such case file")
    try:
        data = tomllib.loads(file.read_text())
    except tomllib.TOMLDecodeError as e:
        raise CaseError(file, "", f"not valid TOML: {e}") from None
    except UnicodeDecodeError:
        raise CaseError(file, "", "not UTF-8 text") from None
    data = apply_overrides(data, overrides or [])
    try:
        case = Case.model_validate(data)
    except ValidationError as e:
        field, reason = format_validation_error(e, data)
        raise CaseError(file, field, reason) from None
    return case, file.parent.resolve()


def resolved_dict(case: Case) -> dict:
    """The case with every default filled in, JSON-able (for resolved.json)."""
    return case.model_dump(mode="json")


def case_hash(case: Case) -> str:
    """SHA-256 of the resolved case (stable key order): identifies a configuration."""
    blob = json.dumps(resolved_dict(case), sort_keys=True).encode()
    return hashlib.sha256(blob).hexdigest()
