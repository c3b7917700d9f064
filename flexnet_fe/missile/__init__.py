"""Missile models (issue 3): ``[missile]`` config (config), geometry and rigid-body properties
(geometry, mass), contact shapes for numba kernels (shapes), Gmsh fin/body meshes (mesh) and
offscreen pictures (picture). All in the body frame B of :mod:`flexnet_fe.frames`."""
