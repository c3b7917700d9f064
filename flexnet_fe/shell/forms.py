"""Flat-shell forms: membrane + Reissner–Mindlin bending + transverse shear (MITC4 type).

Formulation (why): each fin is flat, so the shell is a plate with membrane action. The unknown
is one blocked P1 (bilinear, quadrilateral) field with 5 components per node,
``U = (u_x, u_y, u_z, θ_1, θ_2)``: the mid-surface displacement u [m] in the body frame B (the
mesh lives in B with gdim = 3, so loads and results need no transformation) and the fibre
rotation θ [rad] in the fin's own in-plane basis (e1, e2). Tangential derivatives are taken
along the constant axes e1, e2 on the manifold mesh, ``∂f/∂s_α = grad(f)·e_α``. With 5 DOFs per
node the stiffness is a block-size-5 matrix (BAIJ, DESIGN.md §2); a flat fin needs no drilling
rotation. Kinematics (fibre through the thickness, z along n):

    u_α(z) = u_α + z θ_α,   w = u·n
    ε  = sym(∇u_t)                      membrane strain
    κ  = sym(∇θ)                        curvature,   ε(z) = ε + z κ
    γ  = ∇w + θ                         transverse shear strain

Energy (plane-stress C, D_m = t C, D_b = t³/12 C, shear stiffness κ_s G t):

    Π = ½ ∫ t ε:Cε + (t³/12) κ:Cκ + κ_s G t γ·γ  dA

Shear locking: the shear term uses the MITC4 assumed strain (Bathe & Dvorkin 1985). The
covariant shear strain γ_ξ = γ·a_ξ (a = columns of the cell Jacobian) is tied at the edge
mid-points (½,0), (½,1) and interpolated linearly in η (γ_η likewise in ξ). It is written in UFL
as a directional reduced integration: the γ_ξγ_ξ term is sampled on the line ξ = ½ with 2 Gauss
points in η, the γ_ηγ_η term on η = ½ with 2 points in ξ, the coupling term at the centre, with
the exact correction for the cell twist h = ∂²x/∂ξ∂η (see ``covariant`` in
:func:`stiffness_forms`), so the tied strains are MITC4's on any quadrilateral. Departure from
textbook MITC4: the metric G^{ij} det J is taken at these sampling points instead of 2 × 2 Gauss
points — identical for parallelograms, a quadrature difference on tapered cells. The constant
strain and curvature patch tests pass on distorted meshes (tests). Unlike 1-point reduced shear
integration it has no spurious w-hourglass mode. The paper gives no shell formulation (it uses a
commercial code); this is our choice.

The membrane part is fully integrated (2 × 2 Gauss): exact for the patch test, stiff in in-plane
bending on coarse meshes (parasitic shear of Q4) — in-plane bending is not the fin's load case.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc

from flexnet_fe.shell.meshio import FinPlane
from flexnet_fe.shell.supports import _SUPPORT_COMPONENTS, NORMAL_FIXED, Support  # noqa: F401

NDOF_NODE = 5
"""DOFs per node: u_x, u_y, u_z [m] (frame B), θ_1, θ_2 [rad] (fin basis e1, e2)."""

_G = 0.5 / np.sqrt(3.0)
# Custom quadrature rules on the reference square [0, 1]² (weights sum to its area 1). Tuples,
# not arrays: ffcx converts them, and UFL warns about arrays in form metadata.
_RULE_XI = {"quadrature_rule": "custom",
            "quadrature_points": ((0.5, 0.5 - _G), (0.5, 0.5 + _G)),
            "quadrature_weights": (0.5, 0.5)}
_RULE_ETA = {"quadrature_rule": "custom",
             "quadrature_points": ((0.5 - _G, 0.5), (0.5 + _G, 0.5)),
             "quadrature_weights": (0.5, 0.5)}
_RULE_CENTRE = {"quadrature_rule": "custom",
                "quadrature_points": ((0.5, 0.5),),
                "quadrature_weights": (1.0,)}


@dataclass(frozen=True)
class ShellMaterial:
    """Linear elastic isotropic fin plate."""

    thickness: float
    """t [m]"""
    youngs_modulus: float
    """E [Pa]"""
    poisson_ratio: float
    """ν [-]"""
    density: float
    """ρ [kg/m³]"""
    yield_strength: float = float("inf")
    """tensile yield strength [Pa], reporting only"""
    shear_correction: float = 5.0 / 6.0
    """κ_s [-]"""

    @property
    def shear_modulus(self) -> float:
        """G = E / (2(1 + ν)) [Pa]"""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def plane_stress_modulus(self) -> float:
        """E' = E / (1 − ν²) [Pa]"""
        return self.youngs_modulus / (1.0 - self.poisson_ratio ** 2)

    @property
    def bending_stiffness(self) -> float:
        """D = E t³ / (12 (1 − ν²)) [N m]"""
        return self.plane_stress_modulus * self.thickness ** 3 / 12.0


def shell_space(mesh) -> fem.FunctionSpace:
    """Blocked P1 space with :data:`NDOF_NODE` components per node (block size 5)."""
    return fem.VectorFunctionSpace(mesh, ("Lagrange", 1), dim=NDOF_NODE)


@dataclass(frozen=True)
class Kinematics:
    """UFL strain measures of a shell field (2 × 2 tensors / 2-vectors in the fin basis)."""

    membrane: object
    """ε, 2×2 [-]"""
    curvature: object
    """κ, 2×2 [1/m]"""
    shear: object
    """γ, 2-vector [-]"""
    u: object
    """mid-surface displacement, 3-vector in B [m]"""
    theta: object
    """fibre rotation, 2-vector in (e1, e2) [rad]"""


def _grad_t(f, e):
    """In-plane gradient of a scalar f as a 2-vector (∂f/∂s_1, ∂f/∂s_2)."""
    g = ufl.grad(f)
    return ufl.as_vector([ufl.dot(g, e[0]), ufl.dot(g, e[1])])


@dataclass(frozen=True)
class FormConstants:
    """Fin axes and material as ``fem.Constant`` (not literals), so one compiled form serves
    every fin and material (the JIT cache key does not depend on their values)."""

    e1: fem.Constant
    e2: fem.Constant
    n: fem.Constant
    thickness: fem.Constant
    """t [m]"""
    plane_stress_modulus: fem.Constant
    """E' = E/(1−ν²) [Pa]"""
    poisson_ratio: fem.Constant
    """ν [-]"""
    shear_stiffness: fem.Constant
    """κ_s G t [N/m]"""


def form_constants(mesh, plane: FinPlane, mat: ShellMaterial) -> FormConstants:
    c = lambda v: fem.Constant(mesh, PETSc.ScalarType(v))  # noqa: E731
    vec = lambda v: fem.Constant(mesh, np.asarray(v, dtype=PETSc.ScalarType))  # noqa: E731
    return FormConstants(e1=vec(plane.e1), e2=vec(plane.e2), n=vec(plane.n),
                         thickness=c(mat.thickness), plane_stress_modulus=c(mat.plane_stress_modulus),
                         poisson_ratio=c(mat.poisson_ratio),
                         shear_stiffness=c(mat.shear_correction * mat.shear_modulus * mat.thickness))


def kinematics(U, k: FormConstants) -> Kinematics:
    """Strains of the shell field ``U`` (blocked 5-vector) for the fin axes (e1, e2, n)."""
    e = (k.e1, k.e2)
    u = ufl.as_vector([U[0], U[1], U[2]])
    theta = ufl.as_vector([U[3], U[4]])
    ut = [ufl.dot(u, e[0]), ufl.dot(u, e[1])]
    grad_ut = ufl.as_matrix([[_grad_t(ut[a], e)[b] for b in range(2)] for a in range(2)])
    grad_th = ufl.as_matrix([[_grad_t(theta[a], e)[b] for b in range(2)] for a in range(2)])
    w = ufl.dot(u, k.n)
    return Kinematics(membrane=ufl.sym(grad_ut), curvature=ufl.sym(grad_th),
                      shear=_grad_t(w, e) + theta, u=u, theta=theta)


def plane_stress(eps, k: FormConstants):
    """σ = E/(1−ν²) [(1−ν) ε + ν tr(ε) I] for a 2×2 strain (plane stress) [Pa]."""
    nu = k.poisson_ratio
    return k.plane_stress_modulus * ((1.0 - nu) * eps + nu * ufl.tr(eps) * ufl.Identity(2))


def _covariant_basis(mesh):
    """Reference tangent vectors a_ξ = ∂x/∂ξ, a_η = ∂x/∂η (Jacobian columns), 3-vectors."""
    J = ufl.Jacobian(mesh)
    return [ufl.as_vector([J[i, k] for i in range(3)]) for k in range(2)]


def cell_twist(mesh) -> fem.Function:
    """DG0 vector h = ∂²x/∂ξ∂η = x₀₀ − x₁₀ − x₀₁ + x₁₁ of each bilinear cell [m] (zero for
    parallelograms), for owned and ghost cells."""
    V0 = fem.VectorFunctionSpace(mesh, ("DG", 0))
    h = fem.Function(V0)
    x = mesh.geometry.x
    c = mesh.geometry.dofmap.array.reshape(-1, 4)  # dolfinx order (0,0),(1,0),(0,1),(1,1)
    tw = x[c[:, 0]] - x[c[:, 1]] - x[c[:, 2]] + x[c[:, 3]]
    dofs = V0.dofmap.list.array.reshape(-1)
    h.x.array.reshape(-1, 3)[dofs] = tw
    return h


def stiffness_forms(V: fem.FunctionSpace, plane: FinPlane, mat: ShellMaterial) -> list:
    """Bilinear forms whose sum is a(U, V) of the flat shell (membrane + bending + MITC4 shear).

    One form per quadrature rule, to be assembled separately and summed: ffcx 0.5.0 mixes up
    the tables of several custom quadrature rules inside one form (measured: on a distorted
    mesh a shear-free field then gets a large spurious energy; each rule alone is exact)."""
    mesh = V.mesh
    c = form_constants(mesh, plane, mat)
    U, W = ufl.TrialFunction(V), ufl.TestFunction(V)
    kU, kW = kinematics(U, c), kinematics(W, c)
    t = c.thickness
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 2})
    # membrane  ∫ t C ε(U) : ε(W) dA  +  bending  ∫ t³/12 C κ(U) : κ(W) dA
    a_mb = (t * ufl.inner(plane_stress(kU.membrane, c), kW.membrane)
            + t ** 3 / 12.0 * ufl.inner(plane_stress(kU.curvature, c), kW.curvature)) * dx
    # shear  ∫ κ_s G t G^{ij} γ_i(U) γ_j(W) dA with the MITC4 covariant strains γ_i (below)
    a_xi, a_eta = _covariant_basis(mesh)
    e = [c.e1, c.e2]
    h = cell_twist(mesh)
    h2 = ufl.as_vector([ufl.dot(h, e[0]), ufl.dot(h, e[1])])
    Gm = ufl.as_matrix([[ufl.dot(a_xi, a_xi), ufl.dot(a_xi, a_eta)],
                        [ufl.dot(a_eta, a_xi), ufl.dot(a_eta, a_eta)]])
    Gi = ufl.inv(Gm)

    def covariant(k: Kinematics, quad: float):
        """MITC4 γ_ξ, γ_η at the sampling points. γ_ξ = ∂w/∂ξ + θ·a_ξ is tied at (½,0), (½,1)
        and interpolated linearly in η. On the line ξ = ½, ∂w/∂ξ is linear in η but θ·a_ξ is
        quadratic, with η² coefficient (∂θ/∂η)·h, so the tied value is
        γ_ξ(½,η) − η(η−1)(∂θ/∂η)·h; ``quad`` = −η(η−1) at the sampling point (1/6 at the
        2-point Gauss points, 1/4 at the centre). Same for γ_η with ξ ↔ η."""
        g = k.shear
        th = k.theta
        a2 = [ufl.as_vector([ufl.dot(a, e[0]), ufl.dot(a, e[1])]) for a in (a_xi, a_eta)]
        dth = [ufl.as_vector([ufl.dot(ufl.grad(th[m]), a) for m in range(2)]) for a in (a_xi, a_eta)]
        g_xi = ufl.dot(g, a2[0]) + quad * ufl.dot(dth[1], h2)
        g_eta = ufl.dot(g, a2[1]) + quad * ufl.dot(dth[0], h2)
        return g_xi, g_eta

    ks = c.shear_stiffness
    q2 = 1.0 / 6.0  # −η(η−1) at η = ½ ± 1/(2√3)
    gU2, gW2 = covariant(kU, q2), covariant(kW, q2)
    gUc, gWc = covariant(kU, 0.25), covariant(kW, 0.25)
    dx_xi = ufl.Measure("dx", domain=mesh, metadata=_RULE_XI)
    dx_eta = ufl.Measure("dx", domain=mesh, metadata=_RULE_ETA)
    dx_c = ufl.Measure("dx", domain=mesh, metadata=_RULE_CENTRE)
    return [a_mb,
            ks * Gi[0, 0] * gU2[0] * gW2[0] * dx_xi,
            ks * Gi[1, 1] * gU2[1] * gW2[1] * dx_eta,
            ks * Gi[0, 1] * (gUc[0] * gWc[1] + gUc[1] * gWc[0]) * dx_c]


def edge_blocks(V: fem.FunctionSpace, facet_tags, tag: int) -> np.ndarray:
    """Local node (block) indices on the tagged edge."""
    fdim = V.mesh.topology.dim - 1
    V.mesh.topology.create_connectivity(fdim, 0)
    return fem.locate_dofs_topological(V, fdim, facet_tags.find(tag))


def _tangential_rotation(V, blocks: np.ndarray, plane: FinPlane) -> int:
    """Which rotation component (3 = θ1, 4 = θ2) is the tilt along an edge through the nodes
    ``blocks``: θ1 for an edge along e1, θ2 along e2; ValueError otherwise."""
    x = V.tabulate_dof_coordinates()[blocks]
    pts = np.concatenate(V.mesh.comm.allgather(x))
    if len(pts) < 2:
        raise ValueError("edge has fewer than 2 nodes")
    d = pts.max(axis=0) - pts.min(axis=0)
    s = np.abs([d @ plane.e1, d @ plane.e2])
    if min(s) > 1e-9 * max(s):
        raise ValueError("simply_supported_hard needs an edge along e1 or e2 of the fin basis")
    return 3 if s[0] > s[1] else 4


def edge_dofs(V: fem.FunctionSpace, facet_tags, tag: int, support: Support,
              plane: FinPlane | None = None) -> np.ndarray:
    """Local unrolled DOF indices (block size 5) fixed by ``support`` on the tagged edge
    (the w = 0 constraint of the simple supports is not a DOF: see :data:`NORMAL_FIXED`)."""
    support = Support(support)
    blocks = edge_blocks(V, facet_tags, tag)
    comps = list(_SUPPORT_COMPONENTS[support])
    if support is Support.SIMPLY_SUPPORTED_HARD:
        comps.append(_tangential_rotation(V, blocks, plane))
    comps = np.array(comps, dtype=np.int64)
    return (blocks[:, None] * NDOF_NODE + comps[None, :]).ravel().astype(np.int64)
