"""Explicit dolfinx shell solver for the missile's wings and rudders (issue 5).

Modules: ``config`` (the ``[shell]`` table, :class:`FinSpec`), ``meshio`` (fin meshes, fin
plane, test plates), ``forms`` (flat shell: membrane + Reissner–Mindlin bending + MITC4 shear),
``mass`` (lumped mass, rotary-inertia scaling), ``model`` (K and M of a fin), ``explicit``
(central differences, critical step, load histories), ``recovery`` (nodal surface stresses, peak, error estimate), ``kernel`` (compiled step), ``solve`` (run driver), ``stage``
(the pipeline stage :func:`flexnet_fe.shell.stage.run_shell`). The contact-load transfer is
:mod:`flexnet_fe.shell.transfer`.
"""
