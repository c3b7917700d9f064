"""The stage registry: for each stage, stated once, the case tables it needs and reads, the
upstream stages whose outputs it reads, whether it runs distributed under MPI, and its adapter
(a :class:`StageContext` → the explicit arguments of the stage function, which knows nothing
about run directories or case files).

This module imports no physics at import time (``flexnet --help`` and ``validate`` stay light).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Any, Callable

from flexnet_fe.runs import FIN_CONTACTS, HISTORY, SHELL_MESHES, StageContext


class Stage(str, Enum):
    """The pipeline's stages, in the order they run."""

    deploy = "deploy"
    collide = "collide"
    shell = "shell"
    flight = "flight"


STAGE_ORDER = tuple(Stage)


def _air(case):
    from flexnet_fe.atmosphere import isa

    return isa(case.atmosphere.altitude)


def deploy(ctx: StageContext) -> dict:
    from flexnet_fe.net.deploy import run_deploy

    c = ctx.case
    return run_deploy(c.net, c.deploy, _air(c), ctx.stage_dir, ctx.log)


def collide(ctx: StageContext) -> dict:
    """Under ``collide.fin_coupling = "staggered"`` the impact is run twice around the loaded fins'
    shell runs (``shell.coupling``), else once."""
    c = ctx.case
    deploy_dir = ctx.stage_output("deploy") if Stage.deploy in _collide_upstream(c) else None
    if _collide_reads_shell(c):
        from flexnet_fe.shell.coupling import run_staggered

        return run_staggered(c.net, c.deploy, c.missile, c.collide, c.shell, _air(c), deploy_dir, ctx.stage_dir,
                             ctx.log)
    from flexnet_fe.collide.stage import run_collide

    return run_collide(c.net, c.deploy, c.missile, c.collide, _air(c), deploy_dir, ctx.stage_dir, ctx.log)


def _collide_reads_shell(case) -> bool:
    return case.collide.fin_coupling.value == "staggered"


def shell(ctx: StageContext) -> dict:
    """Distributed under MPI: every rank calls it; rank 0 alone writes the meshes (Gmsh) and the
    other ranks wait for them; the solver's XDMF/HDF5 writes are collective."""
    from mpi4py import MPI

    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell.stage import fin_specs, run_shell

    c, comm = ctx.case, ctx.comm or MPI.COMM_WORLD
    # Meshes are rebuilt from the case's own missile table (0.3–1.5 s), never taken stale from meshes/.
    mesh_paths = write_meshes(c.missile, ctx.stage_dir / SHELL_MESHES) if comm.rank == 0 else None
    mesh_paths = comm.bcast(mesh_paths, root=0)
    fins = fin_specs(build_missile(c.missile).fins, mesh_paths)
    collide_dir = ctx.stage_output("collide")
    return run_shell(c.shell, fins, collide_dir / FIN_CONTACTS, collide_dir / HISTORY,
                     ctx.stage_dir, ctx.log, comm)


def flight(ctx: StageContext) -> dict:
    from flexnet_fe.flight.stage import run_flight

    c = ctx.case
    shell_dir = ctx.stage_output("shell") if Stage.shell in _flight_upstream(c) else None
    return run_flight(c.flight, c.atmosphere.altitude, ctx.stage_dir, ctx.log, shell_dir, missile=c.missile)


def _collide_upstream(case) -> tuple[Stage, ...]:
    return (Stage.deploy,) if case.collide.net_source.value == "deploy_max_area" else ()


def _flight_upstream(case) -> tuple[Stage, ...]:
    return (Stage.shell,) if case.flight.damage_from_shell else ()


@dataclass(frozen=True)
class StageSpec:
    """One stage of the pipeline.

    needs        case tables that must be present for the stage to run
    reads        every case table whose values can change the stage's results (hashed)
    reads_also   ``case → further tables`` read only under some settings (hashed with ``reads``)
    upstream     ``case → stages whose outputs this stage reads``
    run          the adapter ``StageContext → summary section``
    distributed  True: under ``mpirun`` every rank calls ``run``; False: rank 0 alone
    """

    needs: tuple[str, ...]
    reads: tuple[str, ...]
    upstream: Callable[[Any], tuple[Stage, ...]]
    run: Callable[[StageContext], dict]
    distributed: bool = False
    reads_also: Callable[[Any], tuple[str, ...]] = lambda case: ()


REGISTRY: dict[Stage, StageSpec] = {
    Stage.deploy: StageSpec(("net",), ("atmosphere", "net", "deploy"), lambda case: (), deploy),
    Stage.collide: StageSpec(("net", "missile", "collide"), ("atmosphere", "net", "deploy", "missile", "collide"),
                             _collide_upstream, collide,
                             reads_also=lambda case: ("shell",) if _collide_reads_shell(case) else ()),
    Stage.shell: StageSpec(("missile", "collide", "shell"), ("missile", "shell"),
                           lambda case: (Stage.collide,), shell, distributed=True),
    Stage.flight: StageSpec(("missile", "flight"), ("atmosphere", "missile", "flight"), _flight_upstream, flight),
}

STAGE_FUNCS = {s: spec.run for s, spec in REGISTRY.items()}
"""``{stage: adapter}`` (kept for callers that inject their own stage functions)."""


def pipeline_order_error(stages) -> str | None:
    """None when ``stages`` are distinct and in pipeline order, else the reason naming the order."""
    names = [Stage(s).value for s in stages]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        return f"stage '{dup}' is listed twice"
    right = [s.value for s in STAGE_ORDER if s.value in names]
    if names != right:
        return f"stages must be listed in pipeline order: {', '.join(right)}"
    return None
