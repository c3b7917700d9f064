"""Case files: ``cases/<name>/case.toml`` → a validated, frozen :class:`Case` (SI units).

Every table of the case file is a :class:`~flexnet_fe.schema.Section` owned by the module that
uses it; this module only composes them and turns any problem into one :class:`CaseError` line
naming the file, the dotted field path and the reason. Nothing in a case file is executed.
"""

from __future__ import annotations

import hashlib
import difflib
import json
import re
import tomllib
import typing
from pathlib import Path
from typing import Any

from pydantic import BaseModel, Field, ValidationError, field_validator, model_validator

from flexnet_fe.errors import CaseError
from flexnet_fe.runs import MAX_NAME
from flexnet_fe.stages import REGISTRY, STAGE_ORDER, Stage, pipeline_order_error
from flexnet_fe.schema import Section
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.flight.config import FlightConfig
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.net.config import DeployConfig, NetConfig
from flexnet_fe.shell.config import ShellConfig


STAGE_SECTIONS: dict[Stage, tuple[str, ...]] = {s: spec.needs for s, spec in REGISTRY.items()}
"""The tables each stage needs (from the registry in :mod:`flexnet_fe.stages`)."""


class CaseMeta(Section):
    """The ``[case]`` table."""

    name: str = Field(min_length=1, max_length=MAX_NAME,
                      description="case name: letters, digits and the characters '_', '.', '-' (not "
                                  "starting with '.'), at most 100 characters; the default run directory is runs/<name>")
    description: str = Field("", description="free text shown in reports")
    stages: tuple[Stage, ...] = Field(min_length=1, description="stages `flexnet run` runs, in pipeline order")

    @field_validator("name")
    @classmethod
    def _safe_name(cls, name: str) -> str:
        if name.startswith("."):
            raise ValueError("a name must not start with '.' ('.' and '..' would leave the output folder)")
        bad = sorted(set(re.sub(r"[A-Za-z0-9_.-]", "", name)))
        if bad:
            raise ValueError(f"only letters, digits, '_', '.' and '-' are allowed (found {''.join(bad)!r})")
        return name

    @field_validator("stages")
    @classmethod
    def _in_order(cls, stages: tuple[Stage, ...]) -> tuple[Stage, ...]:
        reason = pipeline_order_error(stages)
        if reason:
            raise ValueError(reason)
        return stages


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

    @model_validator(mode="after")
    def _staggered_coupling_has_a_shell(self) -> "Case":
        if self.collide is None or self.collide.fin_coupling.value != "staggered":
            return self
        if self.shell is None:
            raise ValueError("collide.fin_coupling = 'staggered' needs a [shell] table (the fins' motion is the "
                             "shell's)")
        if self.shell.load is not None:
            raise ValueError("collide.fin_coupling = 'staggered' moves the fins under the collision's loads: it "
                             "cannot be used with [shell.load]")
        return self

    @model_validator(mode="after")
    def _bearing_modulus_is_the_nets(self) -> "Case":
        """shell.bearing_rope_modulus left out = the net's contact modulus (one quantity, one value;
        resolved.json shows it)."""
        if self.shell is not None and self.shell.bearing_rope_modulus is None and self.net is not None:
            shell = self.shell.model_copy(update={"bearing_rope_modulus": self.net.contact_modulus})
            object.__setattr__(self, "shell", shell)  # frozen model: set once, while validating
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


def models_of(annotation) -> list[type[BaseModel]]:
    """The pydantic models inside an annotation (Optional, Union, Annotated unwrapped)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in typing.get_args(annotation) for m in models_of(arg)]


def _parent_models(loc: tuple[Any, ...], data: Any) -> list[type[BaseModel]]:
    """The model(s) that own the last key of ``loc`` (a discriminated union is resolved by the
    raw data's ``kind``)."""
    models: list[type[BaseModel]] = [Case]
    node = data
    for item in loc[:-1]:
        if isinstance(item, int):
            node = node[item] if isinstance(node, list) and item < len(node) else None
            continue
        if isinstance(node, dict) and node.get("kind") == item and item not in node:
            continue  # union tag
        nxt = [m for model in models if item in model.model_fields
               for m in models_of(model.model_fields[item].annotation)]
        node = node.get(item) if isinstance(node, dict) else None
        if isinstance(node, dict) and "kind" in node:
            tagged = [m for m in nxt if "kind" in m.model_fields and m.model_fields["kind"].default == node["kind"]]
            nxt = tagged or nxt
        models = nxt
    return models


def field_paths(model: type[BaseModel] | None = None, prefix: str = "") -> dict[str, list[str]]:
    """Every field of the schema: ``{field name: [dotted paths where it lives]}``."""
    out: dict[str, list[str]] = {}
    for name, info in (model or Case).model_fields.items():
        path = f"{prefix}{name}"
        out.setdefault(name, []).append(path)
        for sub in models_of(info.annotation):
            for k, v in field_paths(sub, path + ".").items():
                out.setdefault(k, []).extend(p for p in v if p not in out.get(k, []))
    return out


def _mentions_bool(annotation: Any) -> bool:
    if annotation is bool or annotation is Any:
        return True
    return any(_mentions_bool(a) for a in typing.get_args(annotation))


def _has_bool(value: Any) -> bool:
    return isinstance(value, bool) or (isinstance(value, list) and any(_has_bool(v) for v in value))


def boolean_for_number(data: Any, models: list[type[BaseModel]] | None = None, prefix: str = "") -> str | None:
    """The dotted path of the first ``true``/``false`` given where the schema wants a number
    (pydantic's lax mode would read it as 1.0 or 0.0), else None. Enum strings and lists for
    tuples stay accepted, which pydantic's strict mode would refuse."""
    if not isinstance(data, dict):
        return None
    for key, value in data.items():
        infos = [m.model_fields[key] for m in (models or [Case]) if key in m.model_fields]
        if not infos:
            continue
        subs = [m for i in infos for m in models_of(i.annotation)]
        if isinstance(value, dict) and subs:
            if "kind" in value:
                subs = [m for m in subs if "kind" not in m.model_fields
                        or m.model_fields["kind"].default == value["kind"]] or subs
            found = boolean_for_number(value, subs, f"{prefix}{key}.")
            if found:
                return found
        elif _has_bool(value) and not any(_mentions_bool(i.annotation) for i in infos):
            return f"{prefix}{key}"
    return None


def unknown_key_hint(loc: tuple[Any, ...], data: Any) -> str:
    """'; did you mean …?' and '; it belongs in [table]' for an unknown key at ``loc``."""
    key = str(loc[-1])
    valid = sorted({k for m in _parent_models(loc, data) for k in m.model_fields})
    hint = ""
    close = difflib.get_close_matches(key, valid, n=3, cutoff=0.6)
    if close:
        hint += f"; did you mean {' or '.join(close)}?"
    here = ".".join(str(p) for p in loc if not isinstance(p, int))
    elsewhere = [p for p in field_paths().get(key, []) if p != here]
    if elsewhere:
        hint += "; '" + key + "' belongs in " + ", ".join(
            f"[{p.rsplit('.', 1)[0]}]" if "." in p else "the top level" for p in elsewhere[:3])
    if not hint:
        hint = f"; valid keys here: {', '.join(valid)}"
    return hint


def format_validation_error(err: ValidationError, data: Any) -> tuple[str, str]:
    """(field path, reason) of the first error, with a count of the others."""
    errors = err.errors(include_url=False)
    first = errors[0]
    field = _dotted(tuple(first["loc"]), data) or "(top level)"
    reason = first["msg"].removeprefix("Value error, ")
    if first["type"] == "extra_forbidden":
        reason = "unknown key" + unknown_key_hint(tuple(first["loc"]), data)
    elif "input" in first and first["type"] not in ("missing",) and not isinstance(first["input"], dict):
        reason += f" (got {_short(first['input'])})"
    if len(errors) > 1:
        reason += f" (+{len(errors) - 1} more error{'s' if len(errors) > 2 else ''})"
    return field, reason


def _short(value: Any, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[:limit] + f"… ({len(text)} characters)"


_BARE_WORD = re.compile(r"^[A-Za-z_][A-Za-z0-9_.+-]*$")


def parse_override(text: str) -> tuple[list[str], Any]:
    """``--set a.b.c=VALUE`` → (["a", "b", "c"], value). VALUE must be one TOML value
    (``1e-3``, ``true``, ``"radar"``, ``[1, 2]``); a bare word that is not TOML (``radar``) is
    taken as a string. Anything else (a second line, a second key, trailing text) is refused."""
    if "=" not in text:
        raise CaseError("--set", text, "expected key=value")
    key, raw = text.split("=", 1)
    path = [p.strip() for p in key.strip().split(".")]
    if not key.strip() or not all(path):
        raise CaseError("--set", text, "empty key or empty part in the dotted key")
    if "\n" in raw or "\r" in raw:
        raise CaseError("--set", key.strip(), "the value must be a single TOML value on one line")
    try:
        parsed = tomllib.loads(f"v = {raw}")
    except tomllib.TOMLDecodeError:
        if _BARE_WORD.match(raw.strip()):
            return path, raw.strip()
        raise CaseError("--set", key.strip(), f"not a single TOML value: {raw!r} "
                        "(quote strings: --set 'missile.name=\"my missile\"')") from None
    if list(parsed) != ["v"]:
        raise CaseError("--set", key.strip(), f"not a single TOML value: {raw!r}")
    return path, parsed["v"]


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
    flagged = boolean_for_number(data)
    if flagged:
        raise CaseError(file, flagged, "expected a number, got a boolean (true/false)")
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
