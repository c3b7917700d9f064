"""Case-file sections of the net deployment: ``[net]`` (traction or rotary) and ``[deploy]``.

Defaults are the paper's §V-A values where the paper gives one; where it does not (rope
diameter, launch direction, damping ratio, initial state of the warps) the default is our
documented choice and the field says so.
"""

from __future__ import annotations

from enum import Enum
from typing import Annotated, Literal

from pydantic import Field

from flexnet_fe.schema import NonNegative, Positive, Section


class WarpInitialState(str, Enum):
    """How the rotary net's warp and weft nodes move at t = 0 (the paper does not say)."""

    RIGID_ROTATION = "rigid_rotation"
    """Every node turns with the hub's initial spin: v = ω ẑ × r (DESIGN §5 lead)."""
    REST = "rest"
    """Rope nodes start with the hub's translation only; only the hub and the tip masses spin."""


class RopeNet(Section):
    """The rope of either net (paper §V-A gives E and ρ for the traction net; the rotary net
    uses the same rope)."""

    youngs_modulus: Positive = Field(1.0e6, description="rope Young's modulus E [Pa] (paper: 1 MPa)")
    density: Positive = Field(1000.0, description="rope material density [kg/m^3] (paper: 1000)")
    damping_ratio: NonNegative = Field(0.05, lt=1.0, description=(
        "damping ratio ζ of the axial mode of one bar [-], Eq. (4); not given in the paper"))
    damping_law: Literal["segment", "material"] = Field("segment", description=(
        "how Eq. (4) reads on a subdivided rope (net.subdivisions, collide rope_split / "
        "fin_piece_length): 'segment' = every segment gets c = 2ζ√(μK) from its own stiffness and "
        "end masses (the paper's per-segment law: a finer rope damps less per metre); 'material' = "
        "the rope keeps the viscosity of a whole mesh bar, dashpots in series (c_piece = k c_bar), "
        "so refinement converges to a viscous continuum. Identical for unsplit ropes. See "
        "docs/collide_convergence.md"))
    poisson_ratio: float = Field(0.3, ge=0.0, lt=0.5, description=(
        "Poisson's ratio ν of the rope [-], Eq. (30)-(31) (not given in the paper)"))
    transverse_modulus: Positive | None = Field(None, description=(
        "transverse compressive modulus of the rope's cross-section [Pa], the E1 of the contact law "
        "Eq. (30); None = youngs_modulus (isotropic rope). A fibre rope is much stiffer across "
        "than a 1 MPa axial modulus suggests (see docs/validation.md, collision)"))
    breaking_strength: Positive | None = Field(None, description=(
        "breaking stress of the rope [Pa] on its cross-section π d²/4; a segment whose elastic "
        "tension exceeds it breaks in the collision. None = unbreakable (the paper's model)"))
    slack_offset: float = Field(0.0, description=(
        "LINK167-style offset of one bar [m]: the bar is taut when its length exceeds its rest "
        "length − offset; > 0 pretension, < 0 slack (paper: not given, 0)"))

    @property
    def contact_modulus(self) -> float:
        """The rope's modulus across its section [Pa]: transverse_modulus, else youngs_modulus."""
        return float(self.youngs_modulus if self.transverse_modulus is None else self.transverse_modulus)


class TractionNet(RopeNet):
    """Square traction net pulled open by four corner masses (paper §III-A, §V-A).

    The net lies flat in the x–y plane of the world frame at t = 0, centred on the origin,
    its edges along x and y, unstretched (zero tension) — see ``flexnet_fe.frames``.
    """

    kind: Literal["traction"] = Field("traction", description="net type selector [-]")
    edge_length: Positive = Field(5.0, description="side of the square net [m] (paper: 5 m)")
    mesh_size: Positive = Field(0.05, description="knot spacing of the square mesh [m] (paper: 5 cm)")
    subdivisions: int = Field(1, ge=1, le=16, description=(
        "lumped-mass segments per mesh bar [-]; 1 = one spring between adjacent knots (the "
        "paper's model); >1 adds rope nodes along each bar (refinement studies)"))
    rope_diameter: Positive = Field(4.5e-3, description=(
        "rope diameter d [m]; not given in the paper. Default 4.5 mm: with E = 1 MPa the first "
        "opening reaches the paper's ~100 m^2 (air off; sweep in docs/validation.md)"))
    corner_mass: Positive = Field(1.0, description="mass of each of the four corner masses [kg] (paper: 1 kg)")
    corner_speed: Positive = Field(100.0, description=(
        "launch speed of the corner masses relative to the net centre [m/s] (paper: 100 m/s)"))
    launch_azimuth_deg: float = Field(45.0, ge=0.0, le=90.0, description=(
        "in-plane launch direction of each corner mass [deg], measured from the adjacent edge "
        "(45 = along the diagonal, outwards); not given in the paper"))
    launch_elevation_deg: float = Field(0.0, ge=-89.0, le=89.0, description=(
        "inclination of the launch velocity out of the net plane towards +z (flight "
        "direction) [deg]; 0 = in the net plane; not given in the paper"))


class RotaryNet(RopeNet):
    """Rotary net: a spinning hub with eight radial warps, wefts between adjacent warps and a
    tip mass on each warp (paper §III-B, §V-A). Flat in the x–y plane at t = 0, hub at the
    origin spinning about +z, warps straight and radial, unstretched."""

    kind: Literal["rotary"] = Field("rotary", description="net type selector [-]")
    warps: int = Field(8, ge=3, le=64, description="number of warps n [-] (paper: 8)")
    warp_length: Positive = Field(3.0, description="length of each warp outside the hub [m] (paper: 3 m)")
    mesh_size: Positive = Field(0.03, description="radial spacing of the weft rings [m] (paper: 3 cm)")
    subdivisions: int = Field(1, ge=1, le=16, description=(
        "lumped-mass segments per bar (warp bar or weft chord) [-]; 1 = the paper's model"))
    rope_diameter: Positive = Field(6.0e-3, description=(
        "rope diameter d [m]; not given in the paper. Default 6 mm: the first opening reaches "
        "the paper's ~110 m^2 (air off, warps in rigid rotation; sweep in docs/validation.md)"))
    hub_radius: Positive = Field(0.1, description="radius r0 of the central rotating axis [m] (paper: 0.1 m)")
    hub_length: Positive = Field(0.03, description=(
        "axial length H of the hub cylinder [m]; not given in the paper (2.8 kg of aluminium "
        "of radius 0.1 m is 3 cm long). Warps wind on it only while their first node is within "
        "H/2 of the hub plane"))
    hub_mass: Positive = Field(2.8, description="mass of the central rotating axis [kg] (paper: 2.8 kg)")
    hub_inertia: Positive | None = Field(None, description=(
        "spin moment of inertia J of the hub [kg m^2]; default (None) = solid disc ½ m r0^2 "
        "(the paper gives only mass and radius)"))
    hub_spin: float = Field(10.0, description="initial hub spin ω about +z [rad/s] (paper: 10 rad/s)")
    tip_mass: Positive = Field(0.5, description="mass at the end of each warp [kg] (paper: 0.5 kg)")
    tip_speed: float = Field(30.0, description="initial tangential speed of the tip masses [m/s] (paper: 30 m/s)")
    warp_initial_state: WarpInitialState = Field(WarpInitialState.RIGID_ROTATION, description=(
        "initial velocity of the rope nodes: rigid_rotation (with the hub spin) or rest"))


NetConfig = Annotated[TractionNet | RotaryNet, Field(discriminator="kind")]
"""The ``[net]`` table: a traction or a rotary net, chosen by ``kind``."""


class DeployConfig(Section):
    """The ``[deploy]`` table: how the deployment is simulated and written."""

    duration: Positive = Field(1.0, description="simulated time [s]")
    output_interval: Positive = Field(0.005, description="interval between history rows [s]")
    snapshot_interval: Positive = Field(0.02, description="interval between net snapshots (.vtu) [s]")
    air: bool = Field(True, description=(
        "rope aerodynamic loads Eq. (5)–(10) on/off [-]; the paper's LS-DYNA run probably had none"))
    gravity: bool = Field(True, description="gravity -g ŷ on/off [-] (g from ISA at the altitude)")
    mach: NonNegative = Field(3.0, description=(
        "flight Mach number of the net at opening [-] (paper: 3); the whole net starts with "
        "velocity mach·a ẑ through still air"))
    safety_factor: Positive = Field(0.5, le=1.0, description=(
        "time step = safety_factor × min(spring stability limit, drag time scale) [-]"))
    time_step: Positive | None = Field(None, description=(
        "forced time step [s]; None = from physics. A forced step above the stability limit "
        "is refused (NumericalError)"))
    area_pixel: Positive = Field(0.01, description=(
        "pixel size of the rasterised net area [m]; area error <= perimeter × pixel / 2"))
