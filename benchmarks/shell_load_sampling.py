"""How the fin peak stresses depend on the fin loads' time sampling (``collide.load_interval``).

One collision sampled finely gives every coarser sampling exactly: the collision records each fin
load as its mean force over a sample interval, and the mean over m intervals is the average of the
m means. So the fine run's ``fin_contacts.npz`` is coarsened by m = 1, 2, 4, … and the shell stage
is run on each — the sampling is the only thing that changes (no second collision, whose cut/merge
cadence would move the rope's strikes). Within a coarse sample the events of a fin whose points
fall in the same 0.25 mm cube are merged (forces summed, point |F|-weighted), as the collision
merges a segment's contacts within a sample.

    PYTHONPATH=. .venv/bin/python benchmarks/shell_load_sampling.py coarsen RUN OUT_DIR M
    PYTHONPATH=. .venv/bin/python benchmarks/shell_load_sampling.py shell CASE RUN_DIR NAME
    PYTHONPATH=. .venv/bin/python benchmarks/shell_load_sampling.py table OUT.jsonl LABEL=SHELL_JSON ...
    PYTHONPATH=. .venv/bin/python benchmarks/shell_load_sampling.py plot OUT.jsonl OUT.png

coarsen: copy RUN (its deploy and collide) to OUT_DIR with the loads coarsened by M. shell: the
shell stage of CASE on RUN_DIR/collide, into RUN_DIR/NAME/ and RUN_DIR/NAME.json (no pipeline
bookkeeping: the case's hash is not checked). table: one JSONL row per shell result (label, sample
interval, peaks per fin, wall). plot: peak per fin against the sample interval
(docs/validation.md, "The fin loads' time sampling")."""

from __future__ import annotations

import json
import logging
import shutil
import sys
from pathlib import Path

import numpy as np

FINS = [f"wing_{i}" for i in range(1, 5)] + [f"rudder_{i}" for i in range(1, 5)]


def coarsen(src: Path, dst: Path, m: int) -> None:
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("shell*", ".shell.partial", "run.lock"))
    z = dict(np.load(src / "collide/fin_contacts.npz"))
    t, rs = z["t"], z["row_start"]
    nt = (t.size // m) * m
    ne = rs[nt]
    sample = np.repeat(np.arange(nt) // m, np.diff(rs[:nt + 1]))
    fin, pt, F, w = z["fin"][:ne], z["point"][:ne], z["force"][:ne] / m, z["width"][:ne]
    key = np.column_stack([sample, fin, np.floor(pt / 2.5e-4).astype(np.int64)])
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    nu = uniq.shape[0]
    mag = np.linalg.norm(F, axis=1)
    Fs = np.zeros((nu, 3))
    np.add.at(Fs, inv, F)
    W = np.bincount(inv, mag, minlength=nu)
    P = np.zeros((nu, 3))
    np.add.at(P, inv, pt * mag[:, None])
    P0 = np.zeros((nu, 3))
    np.add.at(P0, inv, pt)
    P0 /= np.bincount(inv, minlength=nu)[:, None]
    P = np.where(W[:, None] > 0, P / np.maximum(W, 1e-300)[:, None], P0)
    ws = np.zeros(nu)
    ws[inv] = w
    z["t"] = t[:nt].reshape(-1, m).mean(axis=1)
    z["row_start"] = np.concatenate([[0], np.cumsum(np.bincount(uniq[:, 0], minlength=nt // m))]).astype(np.int64)
    z["fin"], z["point"], z["force"], z["width"] = uniq[:, 1].astype(np.int32), P, Fs, ws
    np.savez(dst / "collide/fin_contacts.npz", **z)
    print(dst, "samples", z["t"].size, "events", nu, "of", ne)


def shell(case_dir: Path, run: Path, name: str) -> None:
    from flexnet_fe.config import load_case
    from flexnet_fe.missile.build import build_missile
    from flexnet_fe.missile.mesh import write_meshes
    from flexnet_fe.shell.stage import fin_specs, run_shell

    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    c, _ = load_case(case_dir)
    out = run / name
    out.mkdir(parents=True, exist_ok=True)
    fins = fin_specs(build_missile(c.missile).fins, write_meshes(c.missile, out / "meshes"))
    s = run_shell(c.shell, fins, run / "collide/fin_contacts.npz", run / "collide/history.csv", out,
                  logging.getLogger("shell"))
    (run / f"{name}.json").write_text(json.dumps({"shell": s}, indent=1, default=str))


def table(out: Path, items: list[str]) -> None:
    with out.open("w") as f:
        for item in items:
            label, path = item.split("=", 1)
            d = json.loads(Path(path).read_text())
            s = d["shell"]
            dt = s.get("load_sample_interval_s")  # (older runs: named in the label, "…_10us")
            dt = dt if dt is not None else float(label.rsplit("_", 1)[1].removesuffix("us")) * 1e-6
            f.write(json.dumps({"label": label, "load_sample_interval_s": dt,
                                "peak_von_mises_pa": {k: s[k]["peak_von_mises_pa"] for k in FINS},
                                "peak_time_after_load_start_s": {
                                    k: s[k]["peak_time_s"] - s[k]["start_time_s"] for k in FINS},
                                "wall_s": s.get("wall_s"), "setup_wall_s": s.get("setup_wall_s")}) + "\n")


def plot(src: Path, png: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [json.loads(x) for x in src.read_text().splitlines() if x.strip()]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharex=True)
    for ax, group in zip(axes, ("wing", "rudder")):
        for fin in [f for f in FINS if f.startswith(group)]:
            for series, style in (("coarsened", "-o"), ("collision", "s"), ("rope_halved", "^")):
                pts = sorted((r["load_sample_interval_s"] * 1e6, r["peak_von_mises_pa"][fin] / 1e6)
                             for r in rows if r["label"].startswith(series))
                if pts:
                    x, y = zip(*pts)
                    ax.plot(x, y, style, color=f"C{FINS.index(fin) % 4}", ms=4 if series == "coarsened" else 6,
                            mfc="none" if series != "coarsened" else None,
                            label=fin if series == "coarsened" else None)
        if group == "rudder":
            ax.axhline(503, color="k", ls="--", lw=0.8)
            ax.text(0.1, 515, "allowable 503 MPa", fontsize=8)
        ax.set_xscale("log")
        ax.set_xlabel("fin-load sample interval [µs]")
        ax.set_ylabel("structural peak von Mises [MPa]")
        ax.set_title(f"{group}s", fontsize=9)
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("radar × traction: peak fin stress against the fin loads' time sampling\n"
                 "lines: one collision (sampled at 0.078 µs) coarsened; squares: other collisions; "
                 "triangles: rope chords halved", fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=120)


if __name__ == "__main__":
    cmd, *a = sys.argv[1:]
    if cmd == "coarsen":
        coarsen(Path(a[0]), Path(a[1]), int(a[2]))
    elif cmd == "shell":
        shell(Path(a[0]), Path(a[1]), a[2])
    elif cmd == "table":
        table(Path(a[0]), a[1:])
    elif cmd == "plot":
        plot(Path(a[0]), Path(a[1]))
    else:
        raise SystemExit(__doc__)
