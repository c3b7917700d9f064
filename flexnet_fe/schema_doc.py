"""The case-file reference, generated from the pydantic models (``flexnet schema [TABLE]`` and
the README's "Case reference", written by ``scripts/case_reference.py``).

Every field gives its type, default, unit and meaning; the unit is the ``[...]`` of its
description (the schema's convention, ``flexnet_fe/schema.py``).
"""

from __future__ import annotations

import re
import typing
from enum import Enum
from typing import Any, Iterator

from pydantic import BaseModel
from pydantic_core import PydanticUndefined

from flexnet_fe.config import Case, models_of

UNIT = re.compile(r"\[([^\[\]]*)\]")


def _type_name(annotation: Any) -> str:
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _type_name(typing.get_args(annotation)[0])
    if isinstance(annotation, type) and issubclass(annotation, Enum):
        return " | ".join(f'"{m.value}"' for m in annotation)
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return "table"
    if origin in (typing.Union, getattr(__import__("types"), "UnionType", None)):
        return " | ".join(_type_name(a) for a in typing.get_args(annotation)).replace("NoneType", "none")
    if origin is typing.Literal:
        return " | ".join(repr(a).replace("'", '"') for a in typing.get_args(annotation))
    if origin is tuple:
        args = typing.get_args(annotation)
        inner = _type_name(args[0]) + ", ..." if len(args) == 2 and args[1] is Ellipsis else \
            ", ".join(_type_name(a) for a in args)
        return f"[{inner}]"
    return getattr(annotation, "__name__", str(annotation)).replace("NoneType", "none")


def _default(info) -> str:
    if info.is_required():
        return "required"
    value = info.default
    if value is PydanticUndefined:
        return "(computed)"
    if isinstance(value, Enum):
        return f'"{value.value}"'
    if isinstance(value, BaseModel):
        return "(table)"
    if isinstance(value, str):
        return f'"{value}"'
    return "none" if value is None else str(value)


def _limits(info) -> str:
    out = []
    for m in info.metadata:
        for attr, sym in (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤"), ("min_length", "len ≥"),
                          ("max_length", "len ≤")):
            v = getattr(m, attr, None)
            if v is not None:
                out.append(f"{sym} {v:g}" if isinstance(v, float) else f"{sym} {v}")
    ann = info.annotation
    for a in [ann, *typing.get_args(ann)]:  # Positive / NonNegative aliases carry their bounds
        for m in getattr(a, "__metadata__", ()):
            for attr, sym in (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤")):
                v = getattr(m, attr, None)
                if v is not None and f"{sym} {v:g}" not in out:
                    out.append(f"{sym} {v:g}")
    return ", ".join(out)


def rows(model: type[BaseModel], prefix: str) -> Iterator[tuple[str, list[tuple[str, ...]], str]]:
    """(table name, [(field, type, default, unit, meaning)], table doc) for ``model`` and its
    sub-tables, depth first."""
    fields, subs = [], []
    for name, info in model.model_fields.items():
        desc = (info.description or "").strip()
        units = UNIT.findall(desc)
        unit = units[-1] if units else ""
        meaning = re.sub(r"\s+([,;:.)])", r"\1", " ".join(UNIT.sub("", desc).split())).strip().rstrip(";,")
        limits = _limits(info)
        fields.append((name, _type_name(info.annotation) + (f" ({limits})" if limits else ""), _default(info),
                       unit, meaning))
        for sub in models_of(info.annotation):
            subs.append((f"{prefix}.{name}" if prefix else name, sub))
    doc = " ".join((model.__doc__ or "").strip().split("\n\n")[0].split())
    if prefix:
        yield prefix, fields, doc
    for table, sub in subs:
        kind = sub.model_fields.get("kind")
        yield from rows(sub, table if kind is None else f'{table} (kind = "{kind.default}")')


def tables(only: str | None = None) -> list[tuple[str, list[tuple[str, ...]], str]]:
    out = list(rows(Case, ""))
    if only:
        out = [t for t in out if t[0] == only or t[0].startswith(only + " ") or t[0].startswith(only + ".")]
        if not out:
            from flexnet_fe.errors import CaseError

            names = sorted({t[0].split(" ")[0] for t in rows(Case, "")})
            raise CaseError("flexnet schema", only, f"no such table; tables: {', '.join(names)}")
    return out


def schema_text(only: str | None = None) -> str:
    """Plain-text reference for the terminal."""
    lines = []
    for table, fields, doc in tables(only):
        lines.append(f"[{table}]  {doc}")
        for name, typ, default, unit, meaning in fields:
            lines.append(f"  {name} = {default}   {typ}" + (f"  [{unit}]" if unit else ""))
            if meaning:
                lines.append(f"      {meaning}")
        lines.append("")
    return "\n".join(lines)


def schema_markdown() -> str:
    """Markdown tables for the README's case reference."""
    out = []
    for table, fields, doc in tables():
        out.append(f"#### `[{table}]`\n\n{doc}\n\n| field | type | default | unit | meaning |\n|---|---|---|---|---|")
        for name, typ, default, unit, meaning in fields:
            cells = [f"`{name}`", typ, f"`{default}`", unit, meaning]
            out.append("| " + " | ".join(c.replace("|", "\\|").replace("<", "&lt;") for c in cells) + " |")
        out.append("")
    return "\n".join(out)
