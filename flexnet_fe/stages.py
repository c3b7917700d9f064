"""The pipeline's stage adapters: each turns a :class:`StageContext` into the explicit arguments
of its stage function (which knows nothing about run directories or case files)."""

from __future__ import annotations

from flexnet_fe.atmosphere import isa
from flexnet_fe.config import Stage
from flexnet_fe.runs import StageContext


def deploy(ctx: StageContext) -> dict:
    from flexnet_fe.net.deploy import run_deploy

    c = ctx.case
    return run_deploy(c.net, c.deploy, isa(c.atmosphere.altitude), ctx.stage_dir, ctx.log)


def collide(ctx: StageContext) -> dict:
    from flexnet_fe.collide.config import NetSource
    from flexnet_fe.collide.stage import run_collide

    c = ctx.case
    deploy_dir = ctx.stage_output("deploy") if c.collide.net_source is NetSource.deploy_max_area else None
    return run_collide(c.net, c.deploy, c.missile, c.collide, isa(c.atmosphere.altitude), deploy_dir,
                       ctx.stage_dir, ctx.log)


def shell(ctx: StageContext) -> dict:
    from flexnet_fe.missile.geometry import build_missile
    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell.stage import fin_specs, run_shell

    c = ctx.case
    # Meshes are rebuilt from the case's own missile table (0.3–1.5 s), never taken stale from meshes/.
    mesh_paths = write_meshes(c.missile, ctx.stage_dir / "meshes")
    fins = fin_specs(build_missile(c.missile).fins, mesh_paths)
    collide_dir = ctx.stage_output("collide")
    return run_shell(c.shell, fins, collide_dir / "fin_contacts.npz", collide_dir / "history.csv",
                     ctx.stage_dir, ctx.log)


def flight(ctx: StageContext) -> dict:
    from flexnet_fe.flight.stage import run_flight

    c = ctx.case
    shell_dir = ctx.stage_output("shell") if c.flight.damage_from_shell else None
    return run_flight(c.flight, c.atmosphere.altitude, ctx.stage_dir, ctx.log, shell_dir, missile=c.missile)


STAGE_FUNCS = {Stage.deploy: deploy, Stage.collide: collide, Stage.shell: shell, Stage.flight: flight}
