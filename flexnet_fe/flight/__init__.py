"""Flight stage: 6-DOF flight of the (damaged) missile against a turning aircraft (paper §VI).

Modules: ``airframe`` (component build-up of the case's missile: nose, body, 8 fin panels;
damage by panel), ``aero`` (the force law, pure), ``autopilot`` (three-loop design, loop
margins), ``guidance``, ``target``, ``eom``, ``simulate`` (model data, pure right-hand side, RK4
kernel), ``damage`` (fin stress → lost area), ``miss``, ``stage`` (the stage and its sweep),
``plots``, ``outcome`` (an engagement's outcome from its summary: miss, hit, fin margins; the
map over aim point × incidence × net that runs the cases is ``flexnet_fe.engagement_map``).

Frames used by this package (``flexnet_fe.frames`` leaves the flight frame to us)
----------------------------------------------------------------------------------
Case frame P (what ``[flight]`` positions/directions and ``history.csv`` use)
    The paper's engagement coordinates: aircraft at [7000, 0, 0] m, missile at
    [4000, 1000, 500] m. The paper does not say which axis is up; ``flight.vertical_axis``
    chooses ``"y"`` (default: the Chinese/Russian ground frame of the paper's notation, where
    C_y is lift and m_z the pitch moment) or ``"z"``. P is right-handed.

Internal flight frame F (flat, non-rotating Earth; what the equations of motion use)
    Origin = origin of P. ``x_F = x_P``; ``y_F`` = up (gravity is ``-g y_F``); ``z_F = x_F × y_F``.
    With ``vertical_axis = "y"`` F equals P; with ``"z"``: y_F = z_P, z_F = -y_P.
    Geometric altitude of a point is ``[atmosphere].altitude + y_F``: the aircraft starts at the
    altitude of the ``[atmosphere]`` table (the paper gives none). Air density and speed of sound
    follow ISA (``flexnet_fe.atmosphere.isa``) at the current altitude, tabulated before the run.

Missile body frame B (as ``flexnet_fe.frames``)
    ``+x_b`` forward along the axis; at zero roll ``+y_b`` is up and ``+z_b`` to the right
    (``z_b = x_b × y_b``). Attitude: unit quaternion q (w, x, y, z), ``v_F = R(q) v_B``.
    Euler angles (paper Fig. 21, Russian order): yaw ψ about y_F, pitch θ about z', roll φ about
    x_b: ``R = R_y(ψ) R_z(θ) R_x(φ)``. Angle of attack ``α = atan2(-v_b, u_b)`` (nose above the
    velocity → α > 0, lift along +y_b); sideslip-plane incidence ``α' = atan2(-w_b, u_b)``
    (paper's sideslip β = -α' for small angles).
    Tail fins (cruciform, "+"): fin i at roll angle φ_i = i·90° from +y_b towards +z_b
    (0 top, 1 right, 2 bottom, 3 left). A fin deflection is positive by the right-hand rule
    about the fin's outward radial axis.

Open choices of the paper fixed here, all case parameters (``flexnet_fe.flight.config``):
    vertical axis (default y up), aircraft turn direction (default ``left`` = away from the
    missile's lateral offset +z_F), missile launch direction (default along the initial line of
    sight), aircraft altitude (the ``[atmosphere]`` altitude).
"""
