"""Render the shell stage's von Mises stress of each fin offscreen to PNG.

    python postprocess/show_stress.py RUN_DIR [--fin wing_1] [--time 1.5e-3] [--field NAME] [--out DIR]

Reads ``RUN_DIR/shell/<fin>/envelope.xdmf`` (peak over time; the default) or, with ``--time``,
``fields.xdmf`` at the output time nearest the given time [s] (von Mises = maximum over the top,
mid and bottom surface fields unless ``--field`` names one). Writes ``<out>/<fin>_<what>.png``
(default ``RUN_DIR/postprocess/``). Uses EGL offscreen rendering; needs no display.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from flexnet_fe.errors import FlexnetError
from flexnet_fe.report.pictures import render_stress


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run_dir", type=Path)
    p.add_argument("--fin", action="append", help="fin name (repeatable; default: every fin folder)")
    p.add_argument("--time", type=float, help="output time [s] to show from fields.xdmf (default: envelope)")
    p.add_argument("--field", help="cell field to draw instead of von Mises, e.g. max_principal_top_pa")
    p.add_argument("--out", type=Path, help="output folder (default RUN_DIR/postprocess)")
    a = p.parse_args(argv)
    shell = a.run_dir / "shell"
    # fin folders are those holding the shell stage's XDMF output (shell/meshes/ is not a fin)
    fins = a.fin or sorted(d.name for d in shell.glob("*") if d.is_dir()
                           and ((d / "envelope.xdmf").exists() or (d / "fields.xdmf").exists()))
    if not fins:
        print(f"show_stress: no fin folders in {shell}", file=sys.stderr)
        return 2
    out = a.out or a.run_dir / "postprocess"
    failed = 0
    for fin in fins:
        use_fields = a.time is not None or (a.field is not None and a.field.startswith(("von_mises_", "max_principal_")))
        src = shell / fin / ("fields.xdmf" if use_fields else "envelope.xdmf")
        what = a.field or ("von_mises" if use_fields else "peak_von_mises")
        try:
            pic = render_stress(src, out / f"{fin}_{what}.png", time_s=a.time, field=a.field, title=f"fin {fin}")
        except FlexnetError as err:
            print(f"show_stress: {fin}: {err}", file=sys.stderr)
            failed += 1
            continue
        print(f"{pic.png}: {pic.field}, t = {pic.time_s:.6g} s, max {pic.max_pa / 1e6:.6g} MPa")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
