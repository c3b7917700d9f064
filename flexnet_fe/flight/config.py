"""The ``[flight]`` table: engagement, airframe, autopilot, actuator, seeker, damage, sweep.

Defaults: the engagement of paper §VI; the airframe of Zarchan (*Tactical and Strategic Missile
Guidance*, 6th ed., AIAA 2012, ch. 21–23: 1000 lb, 20 ft × 1 ft tail-controlled missile,
converted to SI); the three-loop autopilot and actuator values of Zarchan's ch. 23 example.
Angles that people type are given in degrees through fields named ``*_deg``.
"""

from __future__ import annotations

from enum import Enum

from pydantic import Field, model_validator

from flexnet_fe.schema import Fraction, NonNegative, Positive, Section, Vec3

FT = 0.3048
"""One foot [m] (Zarchan's airframe is specified in feet)."""
LB = 0.45359237
"""One pound mass [kg]."""


class VerticalAxis(str, Enum):
    """Which axis of the paper's engagement coordinates points up (the paper does not say)."""

    y = "y"
    z = "z"


class TurnDirection(str, Enum):
    """Aircraft level-turn direction as seen by its pilot (up = the vertical axis)."""

    left = "left"
    right = "right"


class LaunchDirection(str, Enum):
    """Initial missile velocity direction (the paper gives only the speed)."""

    line_of_sight = "line_of_sight"
    """along the initial line of sight to the aircraft"""
    collision_course = "collision_course"
    """lead angle that would hit the aircraft if it kept flying straight at constant speed"""


class StabilityDamage(str, Enum):
    """Two readings of the paper's "40 % increase of the pitch/yaw stability moment coefficient".

    The static-stability derivatives m_z^α, m_y^β are negative for a stable missile.
    """

    magnitude = "magnitude"
    """m^α → (1 + d)·m^α: the moment grows in magnitude (more stable)"""
    toward_instability = "toward_instability"
    """m^α → m^α + d·|m^α| = (1 − d)·m^α: algebraic increase, towards neutral stability"""


class SweepParameter(str, Enum):
    """What a sweep varies."""

    wing_damage = "wing_damage"
    rudder_effectiveness = "rudder_effectiveness"


class AirframeConfig(Section):
    """Zarchan's missile (ch. 21, Listing 21.2 / 23.1), SI units. Slender-body nose and body,
    linear supersonic (Ackeret 4/β) wing and tail panels; each panel is a triangle (tip chord 0)."""

    mass: Positive = Field(1000.0 * LB, description="missile mass [kg] (Zarchan: 1000 lb)")
    length: Positive = Field(20.0 * FT, description="missile length [m]")
    diameter: Positive = Field(1.0 * FT, description="body diameter = reference length [m]")
    nose_length: Positive = Field(3.0 * FT, description="nose (radome) length [m]")
    x_cg: Positive = Field(10.0 * FT, description="centre of gravity, distance aft of the nose tip [m]")
    x_hinge: Positive = Field(19.5 * FT, description="tail hinge line (tail centre of pressure) aft of the nose tip [m]")
    wing_root_le: Positive = Field(7.0 * FT, description="wing root leading edge aft of the nose tip [m]")
    wing_root_chord: Positive = Field(6.0 * FT, description="wing root chord [m]")
    wing_span: Positive = Field(2.0 * FT, description="span (height) of one wing panel [m]")
    tail_root_chord: Positive = Field(2.0 * FT, description="tail root chord [m]")
    tail_span: Positive = Field(2.0 * FT, description="span (height) of one tail panel [m]")
    axial_force_coefficient: NonNegative = Field(
        0.0, description="axial force coefficient C_A [-] (0: thrust balances drag, Zarchan's constant-speed airframe)")
    roll_inertia: Positive | None = Field(
        None, description="I_xx [kg m^2]; default: solid cylinder m d^2/8 (Zarchan gives only I_yy)")
    pitch_inertia: Positive | None = Field(
        None, description="I_yy = I_zz [kg m^2]; default: Zarchan's m (3 r^2 + L^2)/12")

    @model_validator(mode="after")
    def _stations_inside(self) -> "AirframeConfig":
        for name in ("x_cg", "x_hinge", "wing_root_le", "nose_length"):
            if getattr(self, name) >= self.length:
                raise ValueError(f"{name} must lie inside the missile length {self.length} m")
        if self.wing_root_le + self.wing_root_chord > self.length:
            raise ValueError("wing extends beyond the missile tail")
        return self


class AutopilotConfig(Section):
    """Zarchan's three-loop acceleration autopilot (ch. 23) in pitch and yaw, PD roll-angle hold.
    Gains are designed once for the undamaged airframe at launch and stay fixed."""

    crossover_rad_s: Positive = Field(50.0, description="open-loop crossover frequency ω_cr [rad/s]")
    damping: Positive = Field(0.7, description="closed-loop damping ζ [-]")
    time_constant_s: Positive = Field(0.3, description="closed-loop time constant τ [s]")
    design_load_g: NonNegative = Field(10.0, description="trim acceleration of the design point [g] (Zarchan: 10 g)")
    roll_bandwidth_rad_s: Positive = Field(20.0, description="roll-angle loop natural frequency [rad/s]")
    roll_damping: Positive = Field(0.7, description="roll-angle loop damping [-]")
    max_accel_command_g: Positive = Field(40.0, description="limit on the guidance acceleration command magnitude [g]")
    gravity_compensation: bool = Field(True, description="add +g (up) to the guidance command")


class ActuatorConfig(Section):
    """Second-order fin actuator per fin with position and rate limits (Zarchan ch. 23: 150 rad/s, 0.7)."""

    natural_frequency_rad_s: Positive = Field(150.0, description="actuator natural frequency [rad/s]")
    damping: Positive = Field(0.7, description="actuator damping ratio [-]")
    max_deflection_deg: Positive = Field(30.0, description="fin deflection limit [deg]")
    max_rate_deg_s: Positive = Field(500.0, description="fin rate limit [deg/s]")


class SeekerConfig(Section):
    """Seeker/LOS-rate model: the true inertial LOS rate through a first-order lag."""

    time_constant_s: Positive = Field(0.05, description="seeker/filter time constant [s]")


class DamageConfig(Section):
    """Damage as multipliers on aerodynamic derivatives (paper §VI)."""

    wing_damage: Fraction = Field(0.0, description="d: lift/side-force slopes × (1 − d), stability moments per `stability` [-]")
    stability: StabilityDamage = Field(StabilityDamage.toward_instability,
                                       description="reading of the paper's '40 % increase of the stability moment'")
    rudder_effectiveness: Fraction = Field(1.0, description="e: control force and moment derivatives × e (0 = rudders lost) [-]")


class SweepConfig(Section):
    """A one-parameter sweep run after the nominal engagement (miss vs damage)."""

    parameter: SweepParameter
    values: tuple[Fraction, ...] = Field(min_length=2, description="values of the parameter [-]")


class FlightConfig(Section):
    """The ``[flight]`` table (paper §VI engagement; positions in the case frame P, see
    ``flexnet_fe.flight``)."""

    vertical_axis: VerticalAxis = Field(VerticalAxis.y, description="which axis of the case coordinates is up")
    target_position: Vec3 = Field((7000.0, 0.0, 0.0), description="aircraft initial position [m]")
    target_direction: Vec3 = Field((1.0, 0.0, 0.0), description="aircraft initial velocity direction (horizontal) [-]")
    target_speed: Positive = Field(272.0, description="aircraft speed [m/s]")
    target_load_factor: float = Field(5.0, ge=1.0, description="level-turn load factor n [-] (horizontal accel g√(n²−1))")
    turn_direction: TurnDirection = Field(TurnDirection.left, description="aircraft turn direction")
    maneuver_start: NonNegative = Field(0.0, description="time the aircraft starts turning [s]")
    missile_position: Vec3 = Field((4000.0, 1000.0, 500.0), description="missile initial position [m]")
    missile_speed: Positive = Field(1000.0, description="missile initial speed [m/s]")
    launch_direction: LaunchDirection = Field(LaunchDirection.line_of_sight, description="missile initial heading")
    navigation_constant: Positive = Field(6.0, description="proportional navigation constant N [-]")
    lethal_radius: Positive = Field(5.0, description="hit if the miss distance is at most this [m]")
    dt: Positive = Field(1e-4, description="RK4 time step [s]")
    t_end: Positive = Field(30.0, description="end time if no closest approach happens first [s]")
    output_dt: Positive = Field(1e-3, description="history.csv output interval [s]")
    damage_from_shell: bool = Field(
        False, description="derive wing_damage and rudder_effectiveness from the shell stage's peak stresses "
                           "(flexnet_fe.flight.damage); the stability reading stays [flight.damage].stability")
    damage_allowable_stress: Positive | None = Field(
        None, description="peak von Mises stress above which fin area counts as lost [Pa] "
                          "(needed with damage_from_shell; e.g. the fin material's yield strength)")
    airframe: AirframeConfig = AirframeConfig()
    autopilot: AutopilotConfig = AutopilotConfig()
    actuator: ActuatorConfig = ActuatorConfig()
    seeker: SeekerConfig = SeekerConfig()
    damage: DamageConfig = DamageConfig()
    sweep: SweepConfig | None = None

    @model_validator(mode="after")
    def _checks(self) -> "FlightConfig":
        if self.damage_from_shell and self.damage_allowable_stress is None:
            raise ValueError("damage_from_shell = true needs damage_allowable_stress [Pa]")
        if self.output_dt < self.dt:
            raise ValueError("output_dt must be >= dt")
        if sum(c * c for c in self.target_direction) == 0.0:
            raise ValueError("target_direction must be non-zero")
        up = {"y": 1, "z": 2}[self.vertical_axis.value]
        if abs(self.target_direction[up]) > 1e-12:
            raise ValueError("target_direction must be horizontal (level turn)")
        return self
