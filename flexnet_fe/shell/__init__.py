"""Explicit dolfinx shell solver for the missile's wings and rudders (issues 5, 10).

Modules: ``config`` (the ``[shell]`` table, :class:`FinSpec`), ``meshio`` (fin meshes, fin
plane, test plates), ``forms`` (flat shell: membrane + Reissner–Mindlin bending + MITC4 shear;
supports), ``mass`` (lumped mass, rotary-inertia scaling), ``model`` (K and M of a fin),
``explicit`` (assembly, Lanczos critical step, load histories, the PETSc step), ``kernel``
(the compiled step), ``recovery`` (nodal surface stresses, located peak, error estimate),
``solve`` (run driver for both backends), ``transfer`` (contact loads → nodal forces),
``stage`` (the pipeline stage :func:`flexnet_fe.shell.stage.run_shell`), ``api`` (plates and
fins under a given pressure or nodal-load history), ``navier`` (Reissner–Mindlin plate series,
the reference of the tests).
"""
