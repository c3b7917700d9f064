"""Missile contact shapes and meshes: ns per query inside one @njit loop, compared in one run.

Run: .venv/bin/python benchmarks/bench_missile_shapes.py  (prints one line per measurement)
"""
import tempfile
import time
from pathlib import Path

import numpy as np
from numba import njit

from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.mesh import write_meshes
from flexnet_fe.msh import read_msh_nodes_and_cells
from flexnet_fe.missile.shapes import (body_closest_point, body_closest_scalar, closest_point,
                                       closest_point_scalar, pack_shapes, segment_core_closest)


@njit(cache=True)
def loop_point(pts, shapes):
    acc = 0.0
    for k in range(pts.shape[0]):
        d, n, q, part = closest_point(pts[k], shapes)
        acc += d + n[0] + q[0] + part
    return acc


@njit(cache=True)
def loop_point_scalar(pts, shapes):
    acc = 0.0
    for k in range(pts.shape[0]):
        d, nx, ny, nz, qx, qy, qz, part = closest_point_scalar(pts[k], shapes)
        acc += d + nx + qx + part
    return acc


@njit(cache=True)
def loop_body(pts, s0, s1, s2):
    acc = 0.0
    for k in range(pts.shape[0]):
        d, n, q, part = body_closest_point(pts[k], s0, s1, s2)
        acc += d + n[0] + q[0] + part
    return acc


@njit(cache=True)
def loop_body_scalar(pts, s0, s1, s2):
    acc = 0.0
    for k in range(pts.shape[0]):
        d, nx, ny, nz, qx, qy, qz, part = body_closest_scalar(pts[k], s0, s1, s2)
        acc += d + nx + qx + part
    return acc


@njit(cache=True)
def loop_segment(a, b, s0, s1, s2, s3, s4, s5, s6, s7, s8):
    acc = 0.0
    for k in range(a.shape[0]):
        for i in range(s3.shape[0]):  # every fin core (collide.kernel's narrow phase)
            d, t, qu, qv, crossed = segment_core_closest(a[k], b[k], s3[i], s4[i], s5[i])
            acc += d + t + qu + qv + crossed
    return acc


def best_of(f, *args, repeat=5):
    f(*args)
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f(*args)
        ts.append(time.perf_counter() - t0)
    return min(ts)


def main():
    rng = np.random.default_rng(0)
    n = 200_000
    for preset in ("radar", "infrared"):
        cfg = MissileConfig(preset=preset)
        S = pack_shapes(build_missile(cfg))
        box = np.column_stack([rng.uniform(-3.8, 0.2, n), rng.uniform(-0.6, 0.6, n),
                               rng.uniform(-0.6, 0.6, n)])
        with tempfile.TemporaryDirectory() as d:
            t0 = time.perf_counter()
            paths = write_meshes(cfg, Path(d))
            t_mesh = time.perf_counter() - t0
            t0 = time.perf_counter()
            write_meshes(cfg.model_copy(update={"mesh_size": cfg.mesh_size / 2}), Path(d) / "f")
            t_fine = time.perf_counter() - t0
            nodes = np.vstack([read_msh_nodes_and_cells(p)[0] for p in paths.values()])
        near = np.repeat(nodes, n // len(nodes) + 1, axis=0)[:n]
        near = near + rng.normal(scale=0.01, size=near.shape)
        seg_b = box + rng.normal(scale=0.05, size=box.shape)
        for label, pts in (("box", box), ("near-surface", near)):
            t_p = best_of(loop_point, pts, S)
            t_ps = best_of(loop_point_scalar, pts, S)
            t_b = best_of(loop_body, pts, *S[:3])
            t_bs = best_of(loop_body_scalar, pts, *S[:3])
            print(f"{preset} {label}: closest_point {t_p / n * 1e9:.0f} ns, "
                  f"closest_point_scalar {t_ps / n * 1e9:.0f} ns (x{t_p / t_ps:.2f}); "
                  f"body_closest_point {t_b / n * 1e9:.0f} ns, body_closest_scalar "
                  f"{t_bs / n * 1e9:.0f} ns (x{t_b / t_bs:.2f})")
        t_s = best_of(loop_segment, box, seg_b, *S)
        print(f"{preset}: segment_core_closest over all fins {t_s / n * 1e9:.0f} ns/segment (|b-a| ~ 9 cm); "
              f"write_meshes {t_mesh:.2f} s at h_e={cfg.mesh_size} m, {t_fine:.2f} s at "
              f"h_e={cfg.mesh_size / 2} m")


if __name__ == "__main__":
    main()
