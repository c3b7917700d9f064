"""Base class and shared field types for the case schema (pydantic v2).

Every section of a case file is a :class:`Section`: unknown keys, wrong types, NaN and inf are
refused, values are frozen after validation. Field docs give SI units in brackets, e.g.
``diameter: Positive = Field(4e-3, description="rope diameter [m]")``.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

class Section(BaseModel):
    """A validated, frozen piece of a case file (extra keys forbidden, no NaN/inf)."""

    model_config = ConfigDict(
        extra="forbid", frozen=True, allow_inf_nan=False, strict=False,
        validate_default=True, use_attribute_docstrings=True,
    )


Positive = Annotated[float, Field(gt=0)]
"""A strictly positive float."""
NonNegative = Annotated[float, Field(ge=0)]
"""A float >= 0."""
PoissonRatio = Annotated[float, Field(ge=0, lt=0.5)]
"""Poisson's ratio ν in [0, 0.5)."""
Fraction = Annotated[float, Field(ge=0, le=1)]
"""A number in [0, 1]."""
Vec3 = tuple[float, float, float]
"""A 3-vector (x, y, z)."""
