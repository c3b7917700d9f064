"""The frames every module uses (one place; plots say which frame they show).

World frame W (deploy and collide stages)
    Origin at the net centre at t = 0. ``+z`` is the flight direction of the interceptor
    (the net deploys in the x–y plane and the free stream blows along ``-z`` relative to it);
    in the collision the missile moves along ``+z`` into the net (paper §V-C: "the Z-axis points
    to the direction of the missile's motion"). ``+y`` is up (gravity is ``-g ŷ``; the paper's
    "Y-axis along the direction of the lead weight pointing upwards"); ``x = y × z``.

Missile body frame B (missile geometry, contact loads, shell loads, collision attitude)
    Origin at the nose apex. ``+x_b`` points forward along the missile axis, so the missile
    occupies ``x_b ∈ [-L, 0]``. ``y_b``, ``z_b`` span the cross-section; a fin's roll angle φ
    is measured from ``+y_b`` towards ``+z_b`` about ``+x_b``. Stations (distance aft of the
    nose) are ``s = -x_b``. The centre of gravity is a point of B. Attitude is the unit
    quaternion q = (w, x, y, z) rotating B vectors into W: ``v_W = R(q) v_B``.

Flight frame F (the 6-DOF engagement, flight stage)
    Documented in ``flexnet_fe.flight`` (it follows the paper's engagement coordinates).
"""
