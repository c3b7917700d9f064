"""The ``flexnet`` command. No physics here: parse arguments, load the case, call the pipeline.

Heavy libraries (numba, dolfinx, gmsh, pyvista) are imported inside the commands so that
``flexnet --help`` is instant.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

LOG = logging.getLogger("flexnet")


def _setup_logging(verbose: bool) -> None:
    from flexnet_fe.progress import setup_logging

    setup_logging(logging.DEBUG if verbose else logging.INFO)


def _stage_list(text: str | None):
    from flexnet_fe.config import Stage
    from flexnet_fe.errors import CaseError

    if text is None:
        return None
    out = []
    for name in text.replace(" ", "").split(","):
        try:
            out.append(Stage(name))
        except ValueError:
            raise CaseError("--stages", name, f"unknown stage; choose from "
                            f"{', '.join(s.value for s in Stage)}") from None
    return out


def _check_budget(case, args, stages=None, out=None):
    """Refuse (exit 2) a case that is inconsistent or above the budget (flexnet_fe.budget)."""
    from flexnet_fe.budget import check_budget, estimate
    from flexnet_fe.config import case_file

    costs = estimate(case, case_file(args.case), stages)
    if not getattr(args, "force", False):
        check_budget(costs, case_file(args.case), out)
    return costs


def cmd_validate(args) -> int:
    from flexnet_fe.budget import describe
    from flexnet_fe.config import load_case

    case, _ = load_case(args.case, args.set)
    costs = _check_budget(case, args)
    print(f"{args.case}: ok ({case.case.name}; stages: {', '.join(s.value for s in case.case.stages)})")
    print("estimated cost (flexnet_fe/budget.py; --force skips the budget):\n" + describe(costs))
    return 0


def _out_dir(args, name: str, suffix: str = "") -> Path:
    return Path(args.out) if args.out else Path("runs") / f"{name}{suffix}"


def cmd_run(args) -> int:
    from flexnet_fe.config import load_case
    from flexnet_fe.pipeline import is_root, plan_stages, run_case

    case, case_dir = load_case(args.case, args.set)
    stages = _stage_list(args.stages)
    out = _out_dir(args, case.case.name)
    _check_budget(case, args, plan_stages(case, stages), out)
    summary = run_case(case, case_dir, out, stages, force=args.force)
    if not is_root():
        return 0
    print(f"{case.case.name}: done → {out}")
    if args.report:
        from flexnet_fe.report import build_report
        print(f"  report: {build_report(out)}")
    for stage, section in summary.items():
        keys = [k for k in section if not isinstance(section[k], (dict, list))][:6]
        print(f"  {stage}: " + ", ".join(f"{k}={_fmt(section[k])}" for k in keys))
    return 0


def _fmt(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def cmd_mesh(args) -> int:
    from flexnet_fe.config import load_case
    from flexnet_fe.errors import CaseError
    from flexnet_fe.missile.mesh import write_meshes

    case, _ = load_case(args.case, args.set)
    if case.missile is None:
        raise CaseError(args.case, "missile", "the case has no [missile] table to mesh")
    out = Path(args.out) if args.out else Path("meshes") / case.missile.name
    paths = write_meshes(case.missile, out)
    for name, path in paths.items():
        print(f"{name}: {path}")
    return 0


def cmd_sweep(args) -> int:
    from flexnet_fe.config import case_file, load_case
    from flexnet_fe.runs import SWEEP_TABLE
    from flexnet_fe.sweep import parse_axis, run_many, sweep_variants, without_builtin_sweep

    case, _ = load_case(args.case, args.set)  # fail early on a bad base case
    axes = [parse_axis(a) for a in args.vary]
    variants = sweep_variants(Path(args.case), args.set, axes)
    for v in variants:  # every variant must be a valid case before anything runs
        vcase, _ = load_case(v.case_path, list(v.overrides))
        _check_budget(without_builtin_sweep(vcase), args)
    out = _out_dir(args, case.case.name, "-sweep")
    rows = run_many(variants, out, out / SWEEP_TABLE, jobs=args.jobs, force=args.force, executor=args.executor)
    return _table_result(rows, "variants", out / SWEEP_TABLE)


def cmd_ensemble(args) -> int:
    from flexnet_fe.config import case_file, load_case
    from flexnet_fe.ensemble import case_aim_and_cell, describe, members, run_ensemble
    from flexnet_fe.errors import CaseError
    from flexnet_fe.runs import ENSEMBLE_STATS
    from flexnet_fe.sweep import without_builtin_sweep

    case, _ = load_case(args.case, args.set)  # fail early on a bad base case
    if not args.tolerance > 0.0:
        raise CaseError(str(case_file(args.case)), "--tolerance", f"must be > 0, got {args.tolerance}")
    aim, cell = case_aim_and_cell(case, str(case_file(args.case)), args.cell)
    variants = members(Path(args.case), args.set, aim, cell, args.members)
    for v in variants:  # every member must be a valid case before anything runs
        vcase, _ = load_case(v.case_path, list(v.overrides))
        _check_budget(without_builtin_sweep(vcase), args)
    out = _out_dir(args, case.case.name, "-ensemble")
    stats = run_ensemble(variants, out, args.tolerance, jobs=args.jobs, force=args.force, executor=args.executor)
    print(f"{args.members - len(stats['failed'])}/{args.members} members over a {1e3 * cell:g} mm net cell "
          f"→ {out / ENSEMBLE_STATS}\n" + describe(stats))
    for label in stats["failed"]:
        print(f"  {label}: failed (see its row in the table)")
    return 1 if stats["failed"] else 0


def _table_result(rows, what: str, table: Path) -> int:
    failed = [r for r in rows if r["error"]]
    print(f"{len(rows) - len(failed)}/{len(rows)} {what} done → {table}")
    for r in failed:
        print(f"  {r['label']}: {r['error']}")
    return 1 if failed else 0


def cmd_batch(args) -> int:
    from flexnet_fe.config import load_case
    from flexnet_fe.errors import CaseError
    from flexnet_fe.runs import BATCH_TABLE
    from flexnet_fe.sweep import Variant, run_many, safe_name

    cases = sorted(Path(args.folder).glob("*/case.toml"))
    if not cases:
        raise CaseError(args.folder, "", "no */case.toml below this folder")
    for c in cases:
        load_case(c, list(args.set))
    out = Path(args.out) if args.out else Path("runs")
    variants = [Variant(safe_name(c.parent.name), c, tuple(args.set), sweep_point=False) for c in cases]
    rows = run_many(variants, out, out / BATCH_TABLE, jobs=args.jobs, force=args.force, executor=args.executor)
    return _table_result(rows, "cases", out / BATCH_TABLE)


def cmd_report(args) -> int:
    from flexnet_fe.report import build_report, build_sweep_report
    from flexnet_fe.runs import BATCH_TABLE, ENSEMBLE_TABLE, SWEEP_TABLE, is_run_dir

    target = Path(args.target)
    tables = [target / t for t in (SWEEP_TABLE, BATCH_TABLE, ENSEMBLE_TABLE)] if target.is_dir() else []
    table = next((t for t in tables if t.is_file()), None)
    if args.sweep or (table is not None and not is_run_dir(target)):
        path = build_sweep_report(table or target, args.param or None)
    else:
        path = build_report(target)
    print(f"report: {path}")
    return 0


def cmd_status(args) -> int:
    from flexnet_fe.errors import RunDirError
    from flexnet_fe.io import read_json
    from flexnet_fe.pipeline import stale_running
    from flexnet_fe.runs import RESOLVED, STATUS

    path = Path(args.run_dir) / STATUS
    if not path.is_file():
        raise RunDirError(f"{args.run_dir}: not a run directory (no {STATUS})")
    dead = set(stale_running(args.run_dir))
    resolved = Path(args.run_dir) / RESOLVED
    wanted = read_json(resolved)["case"]["case"]["stages"] if resolved.is_file() else None
    for name, rec in read_json(path)["stages"].items():
        if wanted is not None and name not in wanted and rec.get("state", "pending") == "pending":
            continue  # a stage this case does not have
        state = rec.get("state", "?")
        extra = rec.get("error") or rec.get("stale_reason") or ""
        if name in dead:
            state, extra = "running (stale)", f"process {rec.get('pid')} on {rec.get('host')} is gone"
        elif state == "interrupted":
            extra = f"at {rec.get('interrupted_at')}, outputs up to t = {rec.get('outputs_up_to_s')} s"
        print(f"{name:8s} {state}" + (f": {extra}" if extra else ""))
    return 0


def cmd_schema(args) -> int:
    from flexnet_fe.schema_doc import schema_text

    print(schema_text(args.table), end="")
    return 0


def cmd_study(args) -> int:
    from flexnet_fe.study.run import run_study

    page = run_study(args.study, Path(args.out), args.quick, Path(args.run_dir) if args.run_dir else None)
    print(f"study {args.study}: done → {page}")
    return 0


def _add_study_parser(sub) -> None:
    """The `flexnet study` subcommand (issue 15)."""
    sp = sub.add_parser("study", help="accuracy against cost, stability maps, simplifications and throughput, "
                                      "measured on this machine; writes CSV, PNG and README.md",
                        description="Run a study and write <study>.csv, <study>.json, PNG charts and README.md "
                                    "(rebuilt from every study in the folder) into --out. Studies: deploy, collide, "
                                    "shell, flight (error against an in-run fine reference vs CPU time, Pareto "
                                    "front, shipped default), stability (dt/dt_crit, contact stiffness x dt x "
                                    "speed, damping models), simplify (with/without each simplification, from the "
                                    "stage studies in --out), throughput (kernel speed, scaling, end-to-end time).")
    sp.add_argument("study", choices=("all", "deploy", "collide", "shell", "flight", "stability", "simplify",
                                      "throughput"), help="one study, or all of them in order")
    sp.add_argument("--quick", action="store_true", help="reduced scenes and fewer points (about a minute; CI)")
    sp.add_argument("--out", default="docs/study", help="output folder (default docs/study)")
    sp.add_argument("--run-dir", help="throughput: take the end-to-end stage times from this run directory "
                                      "(default: the full study runs cases/radar_traction itself)")
    sp.set_defaults(func=cmd_study)


def _add_report_parser(sub) -> None:
    """The `flexnet report` subcommand."""
    sp = sub.add_parser("report", help="write report.html for a run directory, or a sweep/batch/ensemble folder "
                                       "or table")
    sp.add_argument("target", help="run directory, sweep/batch/ensemble folder, or a sweep.csv / batch.csv / "
                                   "ensemble.csv")
    sp.add_argument("--sweep", action="store_true", help="TARGET is a sweep or batch table")
    sp.add_argument("--param", action="append", metavar="KEY", help="swept parameter columns (default: detected)")
    sp.set_defaults(func=cmd_report)


def _add_ensemble_parser(sub, add_case, add_pool, add_force) -> None:
    """The `flexnet ensemble` subcommand (``flexnet_fe.ensemble``)."""
    sp = sub.add_parser("ensemble", help="run a case with its aim point spread over one net cell; the headlines' "
                                         "and fin stresses' statistics (resumable)",
                        description="Members identical but for collide.aim_point, moved over one net cell by a "
                                    "low-discrepancy sequence (member 0: the case as given). Writes ensemble.csv "
                                    "(members), ensemble.json (mean, standard error, spread, members needed) and "
                                    "ensemble.png. Why: a fin's peak follows where the rope strikes, a placement "
                                    "no run fixes (docs/validation.md, \"Ensembles\").")
    add_case(sp)
    sp.add_argument("--members", type=_positive_int, default=8, metavar="N", help="runs (default 8)")
    sp.add_argument("--cell", type=float, metavar="M", help="side of the square the aim points cover [m] "
                                                          "(default: [net].mesh_size)")
    sp.add_argument("--tolerance", type=float, default=0.02, metavar="REL",
                    help="a mean is converged when its standard error is at most this share of it (default 0.02)")
    sp.add_argument("--out", help="output folder (default runs/<case name>-ensemble)")
    add_pool(sp)
    add_force(sp, "redo members that are already done (and skip the memory/step budget)")
    sp.set_defaults(func=cmd_ensemble)


def build_parser() -> argparse.ArgumentParser:
    from flexnet_fe import __version__

    p = argparse.ArgumentParser(prog="flexnet", description=DESCRIPTION,
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=EPILOG)
    p.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    p.add_argument("--version", action="version", version=f"flexnet_fe {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    def add_case(sp):
        sp.add_argument("case", help="case directory or its case.toml")
        sp.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a case field with one TOML value, e.g. --set net.rope_diameter=4e-3 "
                             "(repeatable; `flexnet schema` lists the keys)")

    def add_force(sp, what):
        sp.add_argument("--force", action="store_true", help=what)

    def add_pool(sp):
        sp.add_argument("-j", "--jobs", type=_positive_int, default=1, metavar="N",
                        help="runs at a time in a local process pool (default 1)")
        sp.add_argument("--executor", choices=("local", "mpi"), default="local",
                        help="local: -j N processes; mpi: mpi4py.futures workers, launched as "
                             "`mpiexec -n N python -m mpi4py.futures -m flexnet_fe.cli sweep …` (cluster)")

    sp = sub.add_parser("validate", help="check a case file, print its estimated cost and exit")
    add_case(sp)
    add_force(sp, "do not refuse a case above the memory/step budget")
    sp.set_defaults(func=cmd_validate)

    sp = sub.add_parser("run", help="run a case's stages into a run directory (resumes: done stages are skipped)")
    add_case(sp)
    sp.add_argument("--out", help="run directory (default runs/<case name>)")
    sp.add_argument("--stages", help="comma-separated stages to run, in pipeline order (default: the case's "
                                     "[case].stages, skipping those already done with the same inputs)")
    sp.add_argument("--report", action="store_true", help="also write report.html into the run directory")
    add_force(sp, "re-run stages that are already done, and run a case above the memory/step budget")
    sp.set_defaults(func=cmd_run)

    sp = sub.add_parser("status", help="print the state of each stage of a run directory")
    sp.add_argument("run_dir", help="run directory")
    sp.set_defaults(func=cmd_status)

    sp = sub.add_parser("mesh", help="build the missile's fin and body meshes with Gmsh")
    add_case(sp)
    sp.add_argument("--out", help="output folder (default meshes/<missile name>)")
    sp.set_defaults(func=cmd_mesh)

    sp = sub.add_parser("sweep", help="run a case over a grid of parameter values; one CSV table (resumable)")
    add_case(sp)
    sp.add_argument("--vary", action="append", required=True, metavar="KEY=V1,V2,...",
                    help="a swept field and its values (repeatable: the grid is their product)")
    sp.add_argument("--out", help="output folder (default runs/<case name>-sweep)")
    add_pool(sp)
    add_force(sp, "redo variants that are already done (and skip the memory/step budget)")
    sp.set_defaults(func=cmd_sweep)

    _add_ensemble_parser(sub, add_case, add_pool, add_force)

    sp = sub.add_parser("batch", help="run every */case.toml below a folder; one CSV table (resumable)")
    sp.add_argument("folder", help="folder holding case directories")
    sp.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override applied to every case (repeatable)")
    sp.add_argument("--out", help="output folder (default runs/)")
    add_pool(sp)
    add_force(sp, "redo cases that are already done")
    sp.set_defaults(func=cmd_batch)

    _add_report_parser(sub)

    _add_study_parser(sub)

    sp = sub.add_parser("schema", help="list every case-file field with its unit, default and meaning")
    sp.add_argument("table", nargs="?", help="one table, e.g. net, collide, missile.material (default: all)")
    sp.set_defaults(func=cmd_schema)
    return p


DESCRIPTION = "flexnet_fe: airborne net vs missile — deploy, collide, fin shell stresses, flight, report."
EPILOG = """exit codes: 0 done, 1 a stage failed, 2 bad input or unusable run directory,
3 numerical failure, 74 disk/permission error, 130 interrupted (Ctrl-C), 143 terminated (SIGTERM).
Ctrl-C keeps every finished stage; `flexnet run` again resumes at the interrupted stage."""


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError("must be >= 1")
    return value


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    _setup_logging(args.verbose)
    from flexnet_fe.errors import FlexnetError, RunIOError
    from flexnet_fe.runs import interrupt_handled, signal_handlers

    try:
        with signal_handlers():
            return args.func(args)
    except FlexnetError as err:
        print(f"flexnet: error: {err}" if err.exit_code < 128 else f"flexnet: {err}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt as err:  # outside a stage (a stage's interrupt is a StageInterrupted)
        interrupt_handled()
        print("flexnet: interrupted", file=sys.stderr)
        return getattr(err, "exit_code", 130)
    except OSError as err:
        if err.errno is None:
            raise
        e = RunIOError(err)
        print(f"flexnet: error: {e}", file=sys.stderr)
        return e.exit_code


if __name__ == "__main__":
    sys.exit(main())
