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
    # dolfinx calls logging.basicConfig() on import, and ffcx then logs every JIT compile to the
    # root logger: give the root a quiet handler first (basicConfig is then a no-op) and keep our
    # own named logger with its own handler.
    root = logging.getLogger()
    if not root.handlers:
        root.addHandler(logging.NullHandler())
    root.setLevel(logging.WARNING)
    LOG.setLevel(logging.DEBUG if verbose else logging.INFO)
    LOG.propagate = False
    if not LOG.handlers:
        h = logging.StreamHandler(sys.stderr)
        h.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
        LOG.addHandler(h)


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


def cmd_validate(args) -> int:
    from flexnet_fe.config import load_case

    case, _ = load_case(args.case, args.set)
    print(f"{args.case}: ok ({case.case.name}; stages: {', '.join(s.value for s in case.case.stages)})")
    return 0


def cmd_run(args) -> int:
    from flexnet_fe.config import load_case
    from flexnet_fe.pipeline import run_case

    case, case_dir = load_case(args.case, args.set)
    stages = _stage_list(args.stages)
    out = Path(args.out) if args.out else Path("runs") / case.case.name
    summary = run_case(case, case_dir, out, stages)
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
    from flexnet_fe.config import load_case
    from flexnet_fe.sweep import parse_axis, run_many, sweep_points

    case, _ = load_case(args.case, args.set)  # fail early on a bad base case
    axes = [parse_axis(a) for a in args.vary]
    points = sweep_points(axes)
    out = Path(args.out) if args.out else Path("runs") / f"{case.case.name}-sweep"
    jobs = [("_".join(o.split("=", 1)[1] for o in pt).replace("/", "-"), Path(args.case), args.set + pt)
            for pt in points]
    rows = run_many(jobs, out, out / "sweep.csv")
    failed = [r for r in rows if r["error"]]
    print(f"{len(rows) - len(failed)}/{len(rows)} points done → {out / 'sweep.csv'}")
    return 1 if failed else 0


def cmd_batch(args) -> int:
    from flexnet_fe.sweep import run_many

    cases = sorted(Path(args.folder).glob("*/case.toml"))
    if not cases:
        from flexnet_fe.errors import CaseError
        raise CaseError(args.folder, "", "no */case.toml below this folder")
    out = Path(args.out) if args.out else Path("runs")
    rows = run_many([(c.parent.name, c, list(args.set)) for c in cases], out, out / "batch.csv")
    failed = [r for r in rows if r["error"]]
    print(f"{len(rows) - len(failed)}/{len(rows)} cases done → {out / 'batch.csv'}")
    return 1 if failed else 0


def cmd_report(args) -> int:
    from flexnet_fe.report import build_report, build_sweep_report

    if args.sweep:
        path = build_sweep_report(Path(args.target), args.param or None)
    else:
        path = build_report(Path(args.target))
    print(f"report: {path}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="flexnet", description=__doc__.splitlines()[0])
    p.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = p.add_subparsers(dest="command", required=True)

    def add_case(sp):
        sp.add_argument("case", help="case directory or its case.toml")
        sp.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a case field, e.g. --set net.rope_diameter=4e-3 (repeatable)")

    sp = sub.add_parser("validate", help="check a case file and exit")
    add_case(sp)
    sp.set_defaults(func=cmd_validate)

    sp = sub.add_parser("run", help="run a case's stages into a run directory")
    add_case(sp)
    sp.add_argument("--out", help="run directory (default runs/<case name>)")
    sp.add_argument("--stages", help="comma-separated stages to run (default: the case's [case].stages)")
    sp.add_argument("--report", action="store_true", help="also write report.html into the run directory")
    sp.set_defaults(func=cmd_run)

    sp = sub.add_parser("mesh", help="build the missile's fin and body meshes with Gmsh")
    add_case(sp)
    sp.add_argument("--out", help="output folder (default meshes/<missile name>)")
    sp.set_defaults(func=cmd_mesh)

    sp = sub.add_parser("sweep", help="run a case over a grid of parameter values; one CSV table")
    add_case(sp)
    sp.add_argument("--vary", action="append", required=True, metavar="KEY=V1,V2,...",
                    help="a swept field and its values (repeatable: the grid is their product)")
    sp.add_argument("--out", help="output folder (default runs/<case name>-sweep)")
    sp.set_defaults(func=cmd_sweep)

    sp = sub.add_parser("batch", help="run every cases/*/case.toml below a folder; one CSV table")
    sp.add_argument("folder", help="folder holding case directories")
    sp.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override applied to every case (repeatable)")
    sp.add_argument("--out", help="output folder (default runs/)")
    sp.set_defaults(func=cmd_batch)

    sp = sub.add_parser("report", help="write report.html for a run directory (or a sweep/batch table)")
    sp.add_argument("target", help="run directory, or with --sweep a sweep.csv / batch.csv")
    sp.add_argument("--sweep", action="store_true", help="TARGET is a sweep or batch table")
    sp.add_argument("--param", action="append", metavar="KEY", help="swept parameter columns (default: detected)")
    sp.set_defaults(func=cmd_report)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    _setup_logging(args.verbose)
    from flexnet_fe.errors import FlexnetError

    try:
        return args.func(args)
    except FlexnetError as err:
        print(f"flexnet: error: {err}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print("flexnet: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
