"""The ``[collide]`` table of a case file (paper §IV, §V-C)."""

from __future__ import annotations

from enum import Enum

from pydantic import Field, model_validator

from flexnet_fe.contact.models import DampingModel
from flexnet_fe.schema import Fraction, NonNegative, Positive, Section


class NetSource(str, Enum):
    """Where the held net of the impact comes from.

    deploy_max_area  the deploy stage's ``net_state.npz`` (net at maximum area), velocities zeroed
    flat_taut        the net's own topology laid flat in the x–y plane at its rest lengths
    """

    deploy_max_area = "deploy_max_area"
    flat_taut = "flat_taut"


class StiffnessRule(str, Enum):
    """How the contact stiffness K [N/m^m] of Eq. (28) is chosen (never from the time step).

    hertz_eq30   Eq. (30) for crossed cylinders (rope radius r × fin half-thickness h/2 on fins,
                 r × body radius R on the body: R_e = sqrt(R1 R2)), contact modulus
                 E* = E_t/(1 − ν²) with the rope's transverse modulus E_t (``net.transverse_modulus``)
                 and a rigid missile
    given        ``contact_stiffness`` as written in the case, for every part
    """

    hertz_eq30 = "hertz_eq30"
    given = "given"


class ContactLaw(str, Enum):
    """How a rope segment in contact with a part is loaded (``collide.kernel``).

    segment  Eq. (28) once per (segment, part) pair at the segment's closest point: a point law
             per segment, so the total force of a rope pressed on a part at a given depth grows
             with the number of segments in contact — ×2.0 / 3.0 / 5.0 at 1.4 / 0.7 / 0.35 mm
             chords for a rope crossing a fin edge 0.2 mm deep (docs/validation.md, "Line contact")
    line     the linear line-load law q = k_l δ [N per metre of rest length] integrated along each
             segment by a midpoint rule with points h to 2h apart, h = r / ``line_points_per_radius``
             (``kernel._line_contact``); k_l chosen so that a straight unstretched rope crossing the
             part's curved surface gets Eq. (30)'s K δ0^1.5 (``contact.stiffness.line_stiffness``;
             stretched s×, K δ0^1.5 / s, as its mass per length): the total force converges as the
             rope is cut finer. The default since 2026-11-28 (docs/validation.md, "Line contact as the
             default"). It holds less energy than ``segment`` at a sharp point (the radar's nose
             apex) and on an edge crossed deep (to the core: k_l R'³/3 = K R'^2.5/(4√2) against
             0.4 K R'^2.5, 0.44×), so rope bars much longer than the contact that stops them
             (unsplit 5–20 cm bars at 350–500 m/s) tunnel — the run stops and names the part;
             split or cut them (``rope_split``, ``fin_piece_length``)
    """

    segment = "segment"
    line = "line"


class FinCoupling(str, Enum):
    """How the fins' elasticity enters the collision (issue 15 §3; docs/validation.md, "One-way fin
    loading" and "The staggered fin coupling").

    one_way    the fins are rigid in the collision; the shell stage then loads the elastic fins
               with its contact forces (the paper's model)
    staggered  one step of the staggered (Gauss–Seidel) iteration of the coupled problem: the
               impact with rigid fins, the shell's normal displacement of every loaded fin under
               those loads, then the impact again with the fins moving so (``shell.coupling``); the
               second impact is the stage's result. ≈ 2× the impact's CPU plus the fins' shell runs
    """

    one_way = "one_way"
    staggered = "staggered"


class CollideConfig(Section):
    """The ``[collide]`` table: scene, contact law, detection, time step, crop and outputs."""

    net_source: NetSource = Field(NetSource.deploy_max_area,
                                  description="held net of the impact: deploy result at max area or a flat taut net")
    impact_speed: Positive = Field(500.0, description="missile speed relative to the held net [m/s] (paper: 500)")
    incidence_angle: float = Field(0.0, ge=0.0, lt=1.5,
                                   description="angle between the missile axis and world +z, pitched about world x [rad] (paper: 0)")
    roll_angle: float = Field(0.0, ge=-3.1416, le=3.1416,
                              description="right-handed roll of the missile about its axis x_b; 0 puts wing_1 (+y_b) along "
                                          "world +y at zero incidence [rad]")
    aim_point: tuple[float, float] = Field((0.0, 0.0),
                                           description="world (x, y) where the missile axis meets the net centre plane z = 0 [m]")
    standoff: Positive = Field(0.02, description="initial gap between nose apex and the nearest net point along the path [m]")
    duration: Positive = Field(0.012, description=(
        "simulated time [s] (paper: impact lasts < 10 ms); the run goes on past it while the interaction "
        "is not over, up to max_duration (end rule: collide.simulate)"))
    max_duration: Positive | None = Field(None, description=(
        "longest simulated time [s]: after `duration` the run continues until the contact has ended and the "
        "missile's tail is end_clearance past every free net node, or this cap is reached (a warning says "
        "whether force was still acting); None = duration (no extension)"))
    end_clearance: NonNegative = Field(0.1, description=(
        "distance [m] by which the missile's tail must be past the free net nodes, with no contact in the last "
        "output interval, for the interaction to count as over"))
    gravity: bool = Field(False, description="apply gravity -g ŷ (ISA g at the altitude) to net and missile")
    air: bool = Field(False, description=(
        "apply the rope's aerodynamic law Eq. (5)-(8) (as in deploy) to every active rope segment, in air at "
        "rest in the held net's frame, of the ISA density at the atmosphere table's altitude; its work and impulse "
        "are booked (dissipated_air_j, air_impulse_*_ns). false = the paper's assumption 2, no air during the impact"))

    contact_exponent: float = Field(1.5, ge=1.0, le=2.0, description="exponent m of Eq. (28) [-] (Hertz: 1.5)")
    restitution: float = Field(0.5, gt=0.0, le=1.0,
                               description="coefficient of restitution e of Eq. (29) [-] (not given in the paper)")
    damping_model: DampingModel = Field(DampingModel.lankarani_nikravesh,
                                        description="contact damping model (Eq. (29) as printed = lankarani_nikravesh)")
    damping_min_approach_speed: Positive = Field(
        1.0, description="floor of the approach speed v_k in χ = c/v_k (v_k = largest approach speed of the "
                         "contact so far, contact.law.approach_speed) [m/s]")
    friction_coefficient: NonNegative = Field(0.2, description="Coulomb friction μ of Eq. (32) [-] (not given in the paper)")
    friction_regularisation_speed: Positive = Field(
        0.1, description="v_reg of tanh(|v_t|/v_reg) replacing sign(v_t) in Eq. (32) [m/s]")
    stiffness_rule: StiffnessRule = Field(StiffnessRule.hertz_eq30, description="rule for the contact stiffness K")
    contact_law: ContactLaw = Field(ContactLaw.line, description=(
        "'segment': Eq. (28) once per rope segment at its closest point; 'line': a line-load law integrated "
        "along the segment, which converges as the rope is cut finer (ContactLaw)"))
    line_points_per_radius: int = Field(4, ge=1, le=64, description=(
        "points of the 'line' contact law per rope radius r: they are r / this to 2 r / this apart along "
        "the rope [-] (a rope crossing a part's sharpest curvature δ deep touches it over ≥ 2√(2 r δ) = r "
        "at δ = r/8)"))
    contact_stiffness: Positive | None = Field(None, description="K for stiffness_rule = 'given' [N/m^m]")
    rope_split: int = Field(1, ge=1, le=64, description=(
        "split every rope segment whose both ends lie within rope_split_margin of the missile's swept volume "
        "into this many equal segments at collision start (collide.refine; 1 = the deployed net as it is) [-]"))
    rope_split_margin: NonNegative = Field(0.2, description=(
        "distance beyond the missile's bounding radius around the flight path within which rope segments "
        "are split (rope_split) [m]"))
    fin_piece_length: Positive | None = Field(None, description=(
        "longest rope piece near the fins [m]: the part of every rope segment whose capsule passes within "
        "fin_split_margin of a fin's strip (the fin's trace swept along the path) is cut into equal pieces no "
        "longer than this, after rope_split (collide.refine; the length at rest: the rope's tension stretches it, "
        "see fin_piece_chord); None = no refinement at the fins"))
    fin_piece_chord: Positive | None = Field(None, description=(
        "during the run, cut rope whose chord (its current, stretched length) is longer than this into equal "
        "pieces no longer than it [m] where it presses on a fin or is about to (the segments that pressed in an "
        "output interval, their rope neighbours, those within two intervals' travel of a fin), and merge the "
        "pieces back once that rope has left the fins (collide.adapt; the stretch of the paper's 1 MPa rope "
        "makes a piece cut at the start ~10x longer where it presses); None = no cutting during the run"))
    fin_split_margin: NonNegative = Field(0.05, description=(
        "distance from a fin's strip within which rope is cut to fin_piece_length [m]"))
    resolution_check: bool = Field(False, description=(
        "also run the impact with fin_piece_length (and fin_piece_chord, when set) halved and report how far each headline moves "
        "(summary resolution_check: Δv, CFC peak, impulse, contact duration, per-fin impulse); a "
        "move beyond resolution_tolerance is a warning (collide.resolution). Costs a second impact "
        "at half the pieces (about 2x the first's CPU), run in a second process beside the first on two "
        "cores or more (collide.check.check_beside)"))
    resolution_tolerance: Positive = Field(0.02, description=(
        "largest relative move of a headline under resolution_check that is not flagged [-]"))
    allow_tunnelling: bool = Field(False, description=(
        "finish a run in which a rope centre line reaches a part's core (the rope passes through) and "
        "report the skipped impulse, instead of stopping"))

    dt_safety: Fraction = Field(0.5, gt=0.0, description="time step = safety × stability limit of springs and contact [-]")
    pass_through_fraction: Fraction = Field(
        0.1, gt=0.0, description="travel per step: relative speed × dt ≤ this × min(rope radius, fin half-thickness) [-]")
    far_net_ratio: int = Field(0, ge=0, le=4096, description=(
        "the far net (segments that cannot touch the missile within a window) is stepped once per window of "
        "this many contact steps, the near net every step (impulse method, collide.kernel 'Far net') [-]; "
        "0 = automatic (the stiffest rope segment turns by at most collide.simulate.FAR_PHASE per window, "
        "at most collide.simulate.FAR_RATIO_CAP steps); "
        "1 = every segment every step"))
    crop: bool = Field(True, description="integrate only the net the impact can reach; hold the rest")
    crop_wave_speed_factor: Positive = Field(
        4.0, description="reach = factor × sqrt(E/ρ) × duration (+ margin) around the missile's swept footprint [-]")
    crop_margin: NonNegative = Field(0.2, description="extra reach of the crop [m]")
    output_interval: Positive = Field(1e-5, description="sampling interval of the histories [s]")
    load_interval: Positive | None = Field(None, description=(
        "sampling interval of the fin loads (their mean force over each interval) [s]; it must divide "
        "output_interval into a whole number of parts; unset: output_interval. The peak fin stresses depend "
        "on it (docs/validation.md, \"The fin loads' time sampling\")"))
    cfc_class: Positive = Field(180.0, description=(
        "SAE J211-1 channel frequency class of the filtered missile acceleration in the summary [-] "
        "(collide.metrics; default 180, justified in docs/validation.md)"))
    snapshots: int = Field(24, ge=2, le=1000, description="number of net snapshots written (.vtu + .pvd)")
    fin_coupling: FinCoupling = Field(FinCoupling.one_way, description=(
        "'one_way': fins rigid in the collision (the paper's model); 'staggered': the impact again with the "
        "fins moving as the shell computes them under the rigid impact's loads (FinCoupling; needs the case's shell "
        "table and contact_law = 'line')"))

    @model_validator(mode="after")
    def _consistent(self) -> "CollideConfig":
        """Cross-field checks (each a one-line case error naming the field)."""
        if self.stiffness_rule is StiffnessRule.given and self.contact_stiffness is None:
            raise ValueError("stiffness_rule = 'given' needs contact_stiffness")
        if self.stiffness_rule is not StiffnessRule.given and self.contact_stiffness is not None:
            raise ValueError("contact_stiffness is only used with stiffness_rule = 'given'")
        if self.output_interval > self.duration:
            raise ValueError("output_interval must not exceed duration")
        if self.load_interval is not None:
            parts = self.output_interval / self.load_interval
            if self.load_interval > self.output_interval or abs(parts - round(parts)) > 1e-6 * parts:
                raise ValueError(f"load_interval ({self.load_interval:g} s) must divide output_interval "
                                 f"({self.output_interval:g} s) into a whole number of parts")
        if self.fin_coupling is FinCoupling.staggered and self.contact_law is not ContactLaw.line:
            raise ValueError("fin_coupling = 'staggered' needs contact_law = 'line' (the moving fins are a "
                             "line-law model: collide.model.with_fin_motion)")
        if self.resolution_check and self.fin_piece_length is None:
            raise ValueError("resolution_check needs fin_piece_length (the check halves it)")
        if self.max_duration is not None and self.max_duration < self.duration:
            raise ValueError(f"max_duration ({self.max_duration:g} s) must not be less than duration "
                             f"({self.duration:g} s)")
        return self

    @property
    def loads_per_output(self) -> int:
        """Fin-load samples per output interval (output_interval / load_interval) [-]."""
        return 1 if self.load_interval is None else round(self.output_interval / self.load_interval)

    @property
    def load_dt(self) -> float:
        """The fin loads' sample interval [s]: load_interval, or output_interval when it is not set."""
        return self.output_interval / self.loads_per_output

    @property
    def end_time(self) -> float:
        """Longest simulated time [s]: max_duration, or duration when it is not set."""
        return self.duration if self.max_duration is None else float(self.max_duration)
