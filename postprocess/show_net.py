"""Render net snapshots (deploy or collide stage) offscreen to one PNG.

    python postprocess/show_net.py RUN_DIR [--stage deploy|collide] [--count 6] [--out FILE]

Reads ``RUN_DIR/<stage>/net.pvd`` (line meshes, world frame W, written by the stage) and draws
``--count`` snapshots evenly spread in time, seen along the flight direction z (the x–y plane
of W), coloured by rope tension [N] when the files carry it. Default output
``RUN_DIR/postprocess/<stage>_net.png``. Uses EGL offscreen rendering; needs no display.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from flexnet_fe.errors import FlexnetError
from flexnet_fe.report.pictures import render_net


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("run_dir", type=Path)
    p.add_argument("--stage", choices=("deploy", "collide"), default="deploy")
    p.add_argument("--count", type=int, default=6, help="number of snapshots shown")
    p.add_argument("--out", type=Path, help="PNG file (default RUN_DIR/postprocess/<stage>_net.png)")
    a = p.parse_args(argv)
    out = a.out or a.run_dir / "postprocess" / f"{a.stage}_net.png"
    try:
        times = render_net(a.run_dir / a.stage / "net.pvd", out, count=a.count, title=f"{a.stage}:")
    except FlexnetError as err:
        print(f"show_net: {err}", file=sys.stderr)
        return 1
    print(f"{out}: {len(times)} snapshots, t = " + ", ".join(f"{t:.4g}" for t in times) + " s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
