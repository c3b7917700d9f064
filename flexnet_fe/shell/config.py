"""The ``[shell]`` table and the per-fin input of the shell stage.

Fin material (E, ν, ρ, thickness, yield) comes from the missile model; the shell table holds
only solver settings.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from pathlib import Path
from typing import Literal

from pydantic import Field, model_validator

from flexnet_fe.schema import NonNegative, Positive, Section
from flexnet_fe.shell.supports import Support


class FinSelection(str, Enum):
    """Which fins the shell stage solves."""

    ALL = "all"
    """every fin of the missile"""
    LOADED = "loaded"
    """only fins that received at least one contact event in the collision stage"""
    NAMED = "named"
    """the fins listed in ``shell.fin_names``"""


class PressureLoad(Section):
    """``[shell.load]``: a uniform pressure history on every solved fin, instead of the
    collision loads (for checking the solver on a fin of one's own; a plate: see
    :mod:`flexnet_fe.shell.api`)."""

    times: tuple[float, ...] = Field(description="sample times, increasing [s]")
    pressure: tuple[float, ...] = Field(
        description="pressure along the fin normal n at the sample times, linear in between, "
                    "zero outside [Pa]")

    @model_validator(mode="after")
    def _check(self) -> "PressureLoad":
        if len(self.times) < 2 or len(self.times) != len(self.pressure):
            raise ValueError("times and pressure need the same length (>= 2)")
        if any(b <= a for a, b in zip(self.times, self.times[1:])):
            raise ValueError("times must increase")
        return self


class ShellConfig(Section):
    """The ``[shell]`` table: explicit shell solver settings."""

    safety_factor: float = Field(0.9, gt=0, le=1,
                                 description="time step = safety_factor × dt_crit [-]")
    rotary_inertia_scale: Literal["auto"] | float = Field(
        "auto",
        description="factor (>= 1) on the rotary inertia ρt³/12, or 'auto': the smallest factor "
                    ">= 1 that lifts the transverse-shear/rotation frequency of an element to its "
                    "membrane frequency (mass scaling as in explicit codes) [-]")
    mass_scaling: float = Field(
        1.0, ge=1.0, le=4.0,
        description="selective mass scaling to a target step [-]: every cell whose step "
                    "estimate (area / longest edge) / c_p is below this × the smallest one gets "
                    "mass on its nodes until it reaches it (flexnet_fe.shell.mass."
                    "selective_mass_scaling); 1 = none. The added mass is in the summary "
                    "(mass_added_rel). radar_traction's eight fins at 1.25 mm, loads sampled "
                    "every 0.3125 µs: 1.25 → 15 % fewer steps, peaks −1.0…+1.7 %; 1.5 → step "
                    "×1.26–1.48, peaks −1.9…+4.7 % (the rudders' strike peaks; the step alone "
                    "moves them ≤ 0.9 %), so radar_traction ships 1.25 (docs/validation.md, "
                    "\"Selective mass scaling\")")
    shear_correction: Positive = Field(5.0 / 6.0, description="transverse shear factor κ [-]")
    rayleigh_alpha: NonNegative = Field(0.0, description="mass-proportional damping α [1/s]")
    rayleigh_beta: NonNegative = Field(0.0, description="stiffness-proportional damping β [s]")
    history_interval: Positive = Field(
        2e-6, description="time between stress samples (history.csv rows, envelope, peak "
                          "search) [s]; rounded to a whole number of steps (at least 1)")
    peak_interval: Positive = Field(
        2.5e-7, description="time between the stress evaluations that find the peaks and the "
                            "envelope (not written to history.csv) [s]; rounded to a whole number "
                            "of steps (at least 1), history_interval then to a multiple of it. "
                            "Under rope strikes sampled every 0.3125 µs the stress peaks are "
                            "1–2 µs wide: at 0.25 µs the nodal peaks read up to 3.7 % low, at "
                            "1 µs up to 15 %; every step costs +45 % of the loops "
                            "(docs/validation.md, the stresses' time sampling)")
    field_interval: Positive | None = Field(
        None, description="time between XDMF field outputs [s]; default: end_time / 10 (plus a "
                          "frame at each fin's peak instant)")
    fins: FinSelection = Field(FinSelection.LOADED, description="all | loaded | named")
    supports: dict[Literal["root", "leading_edge", "tip", "trailing_edge"], Support] = Field(
        default_factory=lambda: {"root": Support.CLAMPED},
        description="edge supports: clamped | simply_supported (w = 0 only) | "
                    "simply_supported_hard | pinned | free; edges not listed are free")
    load: PressureLoad | None = Field(
        None, description="[shell.load]: a pressure history on every solved fin that replaces "
                          "the collision loads (contacts and body acceleration)")
    fin_names: tuple[str, ...] = Field((), description="fins to solve when fins = 'named'")
    end_time: Positive | None = Field(
        None, description="simulated time [s]; default: last contact sample time + end_margin")
    end_margin: NonNegative = Field(
        2e-3, description="time simulated after the last collision sample (with window = 'fin': "
                          "after the fin's own last contact load) when end_time is not given [s]")
    window: Literal["fin", "full"] = Field(
        "fin", description="'fin': simulate each fin from just before its first contact load to "
                           "its last one + end_margin (at rest before: exact; the body "
                           "acceleration outside the window is left out and reported, "
                           "flexnet_fe/shell/schedule.py); 'full': every fin from t = 0 to the "
                           "stage's end")
    workers: int | None = Field(
        None, ge=1, description="threads running the fins' time loops at once (the compiled "
                                "kernel releases the GIL; results do not depend on it); None: the "
                                "cores this process may use; 1: one fin after the other; under "
                                "MPI always 1 [-]")
    lanczos_steps: int = Field(
        40, ge=5, le=400, description="Lanczos steps for λ_max(M⁻¹K), hence dt_crit [-]")
    backend: Literal["auto", "compiled", "petsc"] = Field(
        "auto", description="explicit step: 'compiled' (numba kernel, one process), 'petsc' "
                            "(Mat.mult per step, any number of MPI processes) or 'auto' "
                            "(compiled on one process, petsc under MPI)")
    peak_error_tolerance: Positive = Field(
        0.02, description="a fin's peak von Mises whose estimated relative error exceeds this "
                          "adds a line to summary.shell.warnings [-]")
    peak_check: bool = Field(
        False, description="run each fin again on a mesh with half of local_mesh_size at its loads, from its "
                           "window's start to its peak instant + 0.1 ms, and take the error estimate of its "
                           "peak from the two meshes (2 |move|, Richardson at order 1; summary "
                           "peak_check, peak_error_estimate_kind = 'mesh_halving') instead of the ZZ "
                           "recovery's (shell.stage.check_peaks); needs local_mesh_size")
    strike_envelope: bool = Field(
        False, description="run each loaded fin again with all its contact loads moved in span along its "
                           "leading edge by -1, -1/2, +1/2, +1 rope diameters (kept on the fin), from its "
                           "window's start to its peak instant + 0.1 ms; the largest peak of these and the "
                           "run is the fin's strike_envelope_von_mises_pa, which the verdict holds the fin "
                           "to: the model does not fix where a rope strikes an edge to better than about its "
                           "diameter (shell.strikes, docs/validation.md 'Where the rope strikes')")
    stvenant_radius_factor: NonNegative = Field(
        2.0, description="the reported (structural) peak stress is read outside a zone of radius "
                         "factor × max(fin thickness, rope width) around every contact load "
                         "active at that instant, where shell theory does not hold (bearing "
                         "stress reported apart); 0: no zones [-]")
    local_mesh_size: Positive | None = Field(
        None, description="re-mesh each loaded fin with this element size within (St-Venant "
                          "radius + 2 local sizes) of its contact points, growing to the fin's "
                          "mesh size (Gmsh size field, unstructured quads); None: the missile's "
                          "fin mesh as it is [m]")
    local_mesh_scheme: Literal["full_quad", "blossom"] = Field(
        "full_quad", description="Gmsh recombination of the local_mesh_size mesh: 'full_quad' "
                                 "(meshed at twice the size, every cell split into quads) or "
                                 "'blossom' (triangles paired into quads, no split): same median "
                                 "size and peaks within their error estimate, 1.01-1.36x the "
                                 "step per fin, 1.14x fewer DOF-steps on radar_traction, 2-3x "
                                 "the meshing time (docs/performance.md, issue 10)")
    bearing_rope_modulus: Positive | None = Field(
        None, description="rope transverse modulus for the Hertz contact pressure of face loads; None = "
                          "the net's contact modulus, as the collision's contact stiffness uses it "
                          "(net.transverse_modulus, else net.youngs_modulus) [Pa]")
    bearing_allowable_factor: Positive = Field(
        1.5, description="bearing allowable = factor × fin yield strength (bearing yield of Al "
                         "7075-T6 at e/D = 2 is about 1.5 × tensile yield, MMPDS) [-]")
    energy_growth_limit: Positive = Field(
        10.0, gt=1.0,
        description="stop as unstable when kinetic + strain energy exceeds this factor times "
                    "(initial energy + accumulated |external work|) [-]")
    @model_validator(mode="after")
    def _check(self) -> "ShellConfig":
        if isinstance(self.rotary_inertia_scale, float) and self.rotary_inertia_scale < 1.0:
            raise ValueError("rotary_inertia_scale must be >= 1 or 'auto'")
        if self.fins is FinSelection.NAMED and not self.fin_names:
            raise ValueError("fins = 'named' needs a non-empty fin_names")
        if self.fins is not FinSelection.NAMED and self.fin_names:
            raise ValueError("fin_names is only used with fins = 'named'")
        if self.peak_check and (self.local_mesh_size is None or self.load is not None):
            raise ValueError("peak_check halves local_mesh_size at the contact loads: it needs local_mesh_size "
                             "and the collision's loads (no [shell.load])")
        if self.strike_envelope and self.load is not None:
            raise ValueError("strike_envelope moves the collision's contact loads: it cannot be used with "
                             "[shell.load]")
        return self


@dataclass(frozen=True)
class FinSpec:
    """One fin for the shell stage: mesh file and material (from the missile model).

    mesh_path: Gmsh ``.msh`` (all quadrilaterals, gdim = 3, body frame B [m]) with physical
    groups ``surface``, ``root``, ``leading_edge``, ``tip``, ``trailing_edge``.
    """

    name: str
    mesh_path: Path
    thickness: float
    """plate thickness t [m]"""
    youngs_modulus: float
    """E [Pa]"""
    poisson_ratio: float
    """ν [-]"""
    density: float
    """ρ [kg/m³]"""
    yield_strength: float
    """tensile yield strength [Pa] (reporting only)"""
