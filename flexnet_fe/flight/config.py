"""The ``[flight]`` table: engagement, autopilot, actuator, seeker, damage, damage law, sweep.

Defaults: the engagement of paper §VI; the three-loop autopilot and actuator values of Zarchan's
example (*Tactical and Strategic Missile Guidance*, 6th ed., AIAA 2012, ch. 23). The airframe is
the case's ``[missile]`` (``flexnet_fe.flight.airframe`` builds its aerodynamics from the
geometry); there is no second airframe description here. Angles that people type are given in
degrees through fields named ``*_deg``.
"""

from __future__ import annotations

from enum import Enum

from pydantic import Field, model_validator

from flexnet_fe.schema import Fraction, NonNegative, Positive, Section, Vec3

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


class DamageModel(str, Enum):
    """How wing and rudder damage change the aerodynamics.

    ``geometry``: each damaged panel loses that share of its lift, carry-over and roll damping in
    the component build-up (``flexnet_fe.flight.airframe``): centre of pressure, static margin,
    control power and damping move as the component moments say. The other two are the paper's
    §VI coefficient scalings of whole-airframe derivatives (lift/side-force slopes × (1 − d),
    control derivatives × e), with two readings of its "40 % increase of the pitch/yaw stability
    moment coefficient" (m^α < 0 for a stable missile):
    """

    geometry = "geometry"
    magnitude = "magnitude"
    """m^α → (1 + d)·m^α: the moment grows in magnitude (more stable)"""
    toward_instability = "toward_instability"
    """m^α → m^α + d·|m^α| = (1 − d)·m^α: algebraic increase, towards neutral stability"""


class DamageLaw(str, Enum):
    """Fin stress (shell stage envelope) → share of a fin's aerodynamic area that is lost.

    ``overstressed_area``: a cell whose peak von Mises exceeds ``threshold_factor`` × the fin
    allowable counts as lost (the stress exceeded means the panel no longer holds its shape).
    ``failure_strain``: the linear-elastic peak stress σ_e is turned into an elastic–plastic strain
    by Neuber's rule for an elastic–perfectly-plastic material, ε = σ_e²/(E σ_y) above yield
    (σ_e/E below); a cell whose strain exceeds ``failure_strain`` breaks off (area lost).
    """

    overstressed_area = "overstressed_area"
    failure_strain = "failure_strain"


class SweepParameter(str, Enum):
    """What a sweep varies."""

    wing_damage = "wing_damage"
    rudder_effectiveness = "rudder_effectiveness"


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
    """Aerodynamic damage of the wings and rudders (paper §VI), see :class:`DamageModel`."""

    model: DamageModel = Field(DamageModel.geometry, description="geometry | magnitude | toward_instability")
    wing_damage: Fraction = Field(0.0, description="d: share of every wing's lift lost (geometry), or the paper's "
                                                   "lift × (1 − d) with the stability moment per `model` [-]")
    rudder_effectiveness: Fraction = Field(1.0, description="e: share of every rudder kept (geometry: its lift, "
                                                            "control power and damping), or control derivatives × e [-]")

    @model_validator(mode="before")
    @classmethod
    def _renamed(cls, data):
        if isinstance(data, dict) and "stability" in data:
            raise ValueError("'stability' was renamed 'model' (geometry | magnitude | toward_instability)")
        return data


class DamageLawConfig(Section):
    """The link fin stress → lost aerodynamic area (:class:`DamageLaw`), used with
    ``damage_from_shell``. The allowable stress σ_y is the fin material's (``[missile.material]``),
    read from the shell stage's summary (``allowable_pa``)."""

    law: DamageLaw = Field(DamageLaw.failure_strain, description="overstressed_area | failure_strain")
    threshold_factor: Positive = Field(1.0, description="overstressed_area: lost where σ_vm,peak > factor × σ_allow [-]")
    failure_strain: Positive = Field(
        0.11, description="failure_strain: strain at break [-] (Al 7075-T6: elongation at break 11 %, "
                          "ASM Aerospace Specification Metals / MatWeb)")


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
        False, description="derive each fin's remaining share from the shell stage's peak stresses with "
                           "[flight.damage_law] (flexnet_fe.flight.damage); the model stays [flight.damage].model")
    autopilot: AutopilotConfig = AutopilotConfig()
    actuator: ActuatorConfig = ActuatorConfig()
    seeker: SeekerConfig = SeekerConfig()
    damage: DamageConfig = DamageConfig()
    damage_law: DamageLawConfig = DamageLawConfig()
    sweep: SweepConfig | None = None

    @model_validator(mode="before")
    @classmethod
    def _removed(cls, data):
        if isinstance(data, dict):
            if "damage_allowable_stress" in data:
                raise ValueError("damage_allowable_stress is gone: the fin allowable is the fin material's "
                                 "([missile.material] yield_strength), passed on by the shell stage's summary")
            if "airframe" in data:
                raise ValueError("[flight.airframe] is gone: the airframe is the case's [missile] table "
                                 "(aerodynamics by component build-up, flexnet_fe.flight.airframe)")
        return data

    @model_validator(mode="after")
    def _checks(self) -> "FlightConfig":
        if self.output_dt < self.dt:
            raise ValueError("output_dt must be >= dt")
        if sum(c * c for c in self.target_direction) == 0.0:
            raise ValueError("target_direction must be non-zero")
        up = {"y": 1, "z": 2}[self.vertical_axis.value]
        if abs(self.target_direction[up]) > 1e-12:
            raise ValueError("target_direction must be horizontal (level turn)")
        return self
