"""The ``[missile]`` table of a case file: :class:`MissileConfig`.

A ``preset`` ("radar" or "infrared") fills every field the case file leaves out; any field can be
overridden, including single fields of the ``[missile.wings]``, ``[missile.rudders]`` and
``[missile.material]`` sub-tables (the case file's values are merged onto the preset's).

Sources of the preset values (the paper's Table 1 of missile parameters is lost; paper §V-C only
says the two missiles "are only different in shape and quality [mass]; other parameters including
material and aerodynamic surface parameters are the same"):

* One shared airframe of the AIM-7M Sparrow class (semi-active radar air-to-air missile):
  length 3.66 m, body diameter 0.203 m (8 in), wing span 1.02 m, tail span 0.81 m, launch mass
  231 kg [A. Parsch, "Raytheon AIM-7 Sparrow", Directory of U.S. Military Rockets and Missiles,
  designation-systems.net; Wikipedia "AIM-7 Sparrow"]. Exposed semi-spans follow as
  (span - diameter)/2. Chords, sweep and fin stations are not published; they are estimated from
  public three-view drawings (wings at mid-body, tail rudders at the base) and are marked as
  estimates in ``docs/validation.md`` (missile section).
* Radar preset: tangent-ogive radome, 0.60 m long (≈3 calibres, estimate from drawings).
* Infrared preset: same airframe with a hemispherical seeker dome (nose length = body radius),
  as the paper's Fig. 10(b) blunt dome; its mass follows from the same mean body density, so the
  two differ "in shape and quality" as the paper says.
* Fin material: aluminium alloy 7075-T6 (E = 71.7 GPa, ν = 0.33, ρ = 2810 kg/m³, tensile yield
  503 MPa) [ASM Aerospace Specification Metals / MatWeb, "Aluminum 7075-T6; 7075-T651"].
* Mean body density 1948 kg/m³: calibrated so that the radar preset's total mass (uniform-density
  body of revolution + eight 7075-T6 fin plates) equals the AIM-7M launch mass 231 kg;
  ``tests/missile/test_mass.py`` checks this.
"""

from __future__ import annotations

from enum import Enum
from typing import Any

import numpy as np
from pydantic import Field, model_validator

from flexnet_fe.missile.planform import tip_corner_room
from flexnet_fe.schema import NonNegative, PoissonRatio, Positive, Section, Vec3


class MissilePreset(str, Enum):
    """Which documented default missile to start from."""

    RADAR = "radar"
    INFRARED = "infrared"


class NoseShape(str, Enum):
    """Nose (radome) profile, a solid of revolution from the apex to the body cylinder."""

    TANGENT_OGIVE = "tangent_ogive"
    CONE = "cone"
    HEMISPHERE = "hemisphere"


class MassModel(str, Enum):
    """How mass, centre of gravity and inertia are obtained.

    ``uniform_density``: body of revolution of uniform ``body_density`` plus solid fin plates of
    the fin material (computed by :mod:`flexnet_fe.missile.mass`).
    ``given``: ``mass``, ``cg`` and ``inertia`` are taken from the case file as they are.
    """

    UNIFORM_DENSITY = "uniform_density"
    GIVEN = "given"


class FinMaterial(Section):
    """Isotropic elastic material of the wings and rudders."""

    name: str = Field("Al 7075-T6", description="material name")
    youngs_modulus: Positive = Field(71.7e9, description="Young's modulus E [Pa]")
    poisson_ratio: PoissonRatio = Field(0.33, description="Poisson's ratio ν [-]")
    density: Positive = Field(2810.0, description="density ρ [kg/m^3]")
    yield_strength: Positive = Field(503e6, description="tensile yield strength [Pa]")
    source: str = Field(
        "ASM Aerospace Specification Metals / MatWeb, Aluminum 7075-T6; 7075-T651",
        description="where the values come from",
    )


class FinSetConfig(Section):
    """Four identical flat trapezoidal fins (wings or rudders) in a cruciform layout.

    Each fin is a flat plate in the plane through the missile axis at its roll angle; its root
    chord lies on the body cylinder. Stations are distances aft of the nose apex (``s = -x_b``).
    """

    root_chord: Positive = Field(description="root chord c_r, along the body surface [m]")
    tip_chord: Positive = Field(description="tip chord c_t [m]")
    span: Positive = Field(description="exposed span b, from the body surface to the tip [m]")
    leading_edge_sweep_deg: float = Field(
        ge=-80.0, le=80.0,
        description="leading-edge sweep angle Λ [deg] (explicitly named non-SI input unit)",
    )
    thickness: Positive = Field(description="plate thickness h [m]")
    root_le_station: NonNegative = Field(
        description="station of the root leading edge, distance aft of the nose apex [m]"
    )
    roll_angles_deg: tuple[float, float, float, float] = Field(
        description="roll angle φ of fins 1..4 from +y_b towards +z_b [deg] "
        "(explicitly named non-SI input unit)"
    )
    tip_corner_radius: NonNegative = Field(
        0.0, description="planform radius of the two tip corners (leading edge–tip and "
        "tip–trailing edge) of the rope-contact shape [m]; 0: sharp corners, rounded only by the "
        "half-thickness (missile.planform)"
    )


class MissileConfig(Section):
    """The missile: airframe geometry, fins, fin material, mass model and mesh size (body frame B
    of :mod:`flexnet_fe.frames`). Every field not given in the case file comes from ``preset``."""

    preset: MissilePreset = Field(description="documented default missile (radar | infrared)")
    name: str = Field(description="missile name (meshes go to meshes/<name>/)",
                      pattern=r"^[A-Za-z0-9_.-]+$")
    body_length: Positive = Field(description="total length L, nose apex to base [m]")
    body_diameter: Positive = Field(description="body diameter D = 2R [m]")
    nose_shape: NoseShape = Field(description="nose profile (tangent_ogive | cone | hemisphere)")
    nose_length: Positive = Field(
        description="nose length L_n from the apex to the cylinder [m]; "
        "a hemisphere needs L_n = D/2"
    )
    wings: FinSetConfig = Field(description="the four wings (wing_1..wing_4)")
    rudders: FinSetConfig = Field(description="the four rudders (rudder_1..rudder_4)")
    material: FinMaterial = Field(description="fin material")
    mass_model: MassModel = Field(description="uniform_density | given")
    body_density: Positive = Field(
        description="mean density of the body of revolution for mass_model=uniform_density "
        "[kg/m^3]"
    )
    mass: Positive | None = Field(None, description="total mass for mass_model=given [kg]")
    cg: Vec3 | None = Field(None, description="centre of gravity in B for mass_model=given [m]")
    inertia: tuple[Vec3, Vec3, Vec3] | None = Field(
        None, description="inertia tensor about the CG in B for mass_model=given [kg m^2]"
    )
    mesh_size: Positive = Field(
        description="target element size of the fin shell meshes and the body surface mesh [m]"
    )

    @model_validator(mode="before")
    @classmethod
    def _fill_from_preset(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            return data
        try:
            preset = MissilePreset(data["preset"])
        except (KeyError, ValueError):
            return data  # the field validator reports the missing or unknown preset
        return _merge(PRESETS[preset], data)

    @model_validator(mode="after")
    def _check(self) -> "MissileConfig":
        r = 0.5 * self.body_diameter
        if self.nose_shape is NoseShape.HEMISPHERE and abs(self.nose_length - r) > 1e-9 * r:
            raise ValueError(f"nose_length must equal body_diameter/2 = {r} m for a hemisphere")
        if self.nose_shape is NoseShape.TANGENT_OGIVE and self.nose_length < r:
            raise ValueError(f"a tangent ogive needs nose_length >= body_diameter/2 = {r} m")
        if self.nose_length >= self.body_length:
            raise ValueError("nose_length must be shorter than body_length")
        for label, fs in (("wings", self.wings), ("rudders", self.rudders)):
            te = fs.root_le_station + fs.root_chord
            if fs.root_le_station < self.nose_length or te > self.body_length:
                raise ValueError(
                    f"{label}: root chord [{fs.root_le_station}, {te}] m must lie on the "
                    f"cylinder [{self.nose_length}, {self.body_length}] m"
                )
            room = tip_corner_room(fs.span, fs.root_chord, fs.tip_chord, fs.leading_edge_sweep_deg)
            if fs.tip_corner_radius > room:
                raise ValueError(
                    f"{label}.tip_corner_radius = {fs.tip_corner_radius} m: the rounded tip corners "
                    f"need their arcs to fit on the edges (at most {room:.4g} m for this planform)"
                )
        given = (self.mass, self.cg, self.inertia)
        if self.mass_model is MassModel.GIVEN and any(v is None for v in given):
            raise ValueError("mass_model = 'given' needs mass, cg and inertia")
        if self.inertia is not None:
            inertia = np.array(self.inertia)
            if not np.allclose(inertia, inertia.T, rtol=1e-12, atol=0.0):
                raise ValueError("inertia must be a symmetric tensor")
            if np.linalg.eigvalsh(inertia).min() <= 0.0:
                raise ValueError("inertia must be positive definite")
        if self.mass_model is MassModel.UNIFORM_DENSITY and any(v is not None for v in given):
            raise ValueError("mass, cg, inertia are only read with mass_model = 'given'")
        return self


def _merge(base: dict, over: dict) -> dict:
    """Deep-merge ``over`` onto ``base`` (sub-tables merged key by key)."""
    out = dict(base)
    for k, v in over.items():
        out[k] = _merge(base[k], v) if isinstance(v, dict) and isinstance(base.get(k), dict) else v
    return out


_AIRFRAME: dict[str, Any] = {
    # AIM-7M Sparrow class (sources in the module docstring).
    "body_length": 3.66,
    "body_diameter": 0.203,
    # Wings: span 1.02 m tip to tip -> exposed span (1.02 - 0.203)/2 = 0.4085 m.
    # Chords, sweep, station, thickness: estimates from three-view drawings.
    "wings": {
        "root_chord": 0.80, "tip_chord": 0.20, "span": 0.4085,
        "leading_edge_sweep_deg": 55.0, "thickness": 0.006, "root_le_station": 1.30,
        "roll_angles_deg": (0.0, 90.0, 180.0, 270.0),
    },
    # Rudders (tail): span 0.81 m -> exposed span (0.81 - 0.203)/2 = 0.3035 m.
    "rudders": {
        "root_chord": 0.40, "tip_chord": 0.18, "span": 0.3035,
        "leading_edge_sweep_deg": 35.0, "thickness": 0.004, "root_le_station": 3.24,
        "roll_angles_deg": (0.0, 90.0, 180.0, 270.0),
    },
    "material": {},
    "mass_model": "uniform_density",
    "body_density": 1948.0,
    "mesh_size": 0.02,
}

PRESETS: dict[MissilePreset, dict[str, Any]] = {
    MissilePreset.RADAR: {
        **_AIRFRAME, "preset": "radar", "name": "radar",
        "nose_shape": "tangent_ogive", "nose_length": 0.60,
    },
    MissilePreset.INFRARED: {
        **_AIRFRAME, "preset": "infrared", "name": "infrared",
        "nose_shape": "hemisphere", "nose_length": 0.203 / 2,
    },
}
"""The documented default values of each preset (sources in the module docstring)."""
