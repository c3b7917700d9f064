"""Plots of a collision run, like the paper's Fig. 11–13, 15(a), 16 and 17(a). Each says its frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.simulate import CollisionResult
from flexnet_fe.missile.geometry import Missile
from flexnet_fe.frames import quat_to_matrix


def plot_all(res: CollisionResult, missile: Missile, cfg: CollideConfig, out_dir: Path, title: str,
             prefix: str = "collide_") -> list[Path]:
    """Write the collision plots into ``out_dir``; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    h = res.history
    t_ms = h["t_s"] * 1e3
    paths = []

    fig, ax = plt.subplots(figsize=(7, 4))  # Fig. 12(b), 15(a), 17(a)
    from flexnet_fe.collide.metrics import cfc_filter

    ax.plot(t_ms[1:], h["accel_mag_mps2"][1:], color="0.7", lw=0.6,
            label=f"|a| raw ({cfg.output_interval * 1e6:.0f} µs means)")
    a_f = cfc_filter(h["t_s"][1:], np.column_stack([h[f"accel_body_{c}_mps2"][1:] for c in "xyz"]), cfg.cfc_class)
    for k, c in enumerate("xyz"):
        ax.plot(t_ms[1:], a_f[:, k], lw=0.8, label=f"$a_{{{c}_b}}$ CFC {cfg.cfc_class:g}")
    ax.plot(t_ms[1:], np.linalg.norm(a_f, axis=1), "k", lw=1.0, label=f"|a| CFC {cfg.cfc_class:g}")
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("CG acceleration, body axes [m/s²]")
    ax.set_title(title)
    ax.legend()
    ax.grid(alpha=0.3)
    paths.append(_save(fig, out_dir / f"{prefix}accel.png"))

    fig, ax = plt.subplots(figsize=(7, 4))  # Fig. 12(a)
    v0 = np.array([h["vel_x_mps"][0], h["vel_y_mps"][0], h["vel_z_mps"][0]])
    for c, k in zip("xyz", range(3)):
        ax.plot(t_ms, h[f"vel_{c}_mps"] - v0[k], lw=0.9, label=f"$Δv_{c}$ (world)")
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("missile velocity change, world frame W [m/s]")
    ax.set_title(f"{title}: |Δv|/v max = {np.max(h['dv_rel']):.2e}")
    ax.legend()
    ax.grid(alpha=0.3)
    paths.append(_save(fig, out_dir / f"{prefix}velocity.png"))

    fig, ax = plt.subplots(figsize=(7, 4))  # Fig. 13
    for name, lab in (("pitch", "about world x (pitch)"), ("yaw", "about world y (yaw)"),
                      ("roll", "about world z (roll)")):
        ax.plot(t_ms, h[f"{name}_change_rad"], lw=0.9, label=lab)
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("attitude change [rad]")
    ax.set_title(title)
    ax.legend()
    ax.grid(alpha=0.3)
    paths.append(_save(fig, out_dir / f"{prefix}attitude.png"))

    paths.append(plot_snapshots(res, missile, out_dir / f"{prefix}snapshots.png", title))

    fig, ax = plt.subplots(figsize=(7, 4))
    ld = res.loads
    for i, name in enumerate(ld.fin_names):
        mag = np.zeros(ld.t.size)
        for k in range(ld.t.size):
            rows = slice(ld.row_start[k], ld.row_start[k + 1])
            sel = ld.fin[rows] == i
            mag[k] = np.linalg.norm(ld.force[rows][sel].sum(axis=0))
        if mag.any():
            ax.plot(ld.t * 1e3, mag, lw=0.8, label=str(name))
    ax.set_xlabel("t [ms]")
    ax.set_ylabel("resultant contact force on the fin [N]")
    ax.set_title(f"{title}: fin loads (body frame B)")
    if ax.lines:
        ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    paths.append(_save(fig, out_dir / f"{prefix}fin_loads.png"))
    return paths


def plot_snapshots(res: CollisionResult, missile: Missile, path: Path, title: str, count: int = 6) -> Path:
    """Side views (world z horizontal, world y vertical) of net and missile at ``count`` instants
    (paper Fig. 11, 16)."""
    import matplotlib.pyplot as plt

    idx = np.unique(np.linspace(0, len(res.snap_t) - 1, count).round().astype(int))
    fig, axes = plt.subplots(1, len(idx), figsize=(3 * len(idx), 3.6), sharey=True)
    axes = np.atleast_1d(axes)
    for ax, i in zip(axes, idx):
        x = res.snap_x[i]
        near = np.abs(x[:, 0]) < 0.5  # a slab of the net around the flight path
        ax.plot(x[near, 2], x[near, 1], ",", color="tab:blue")
        r = quat_to_matrix(res.snap_q[i])
        apex = res.snap_apex[i]
        tail = apex - missile.length * r[:, 0]
        ax.plot([apex[2], tail[2]], [apex[1] + missile.radius, tail[1] + missile.radius], "k", lw=1)
        ax.plot([apex[2], tail[2]], [apex[1] - missile.radius, tail[1] - missile.radius], "k", lw=1)
        for fin in missile.fins:
            c = apex + np.asarray(fin.corners) @ r.T
            c = np.vstack([c, c[:1]])
            ax.plot(c[:, 2], c[:, 1], "k", lw=0.6)
        ax.set_title(f"t = {res.snap_t[i] * 1e3:.2f} ms", fontsize=9)
        ax.set_xlabel("z (world) [m]")
        ax.set_aspect("equal", adjustable="datalim")
    axes[0].set_ylabel("y (world) [m]")
    fig.suptitle(f"{title} — side view, net slab |x| < 0.5 m")
    return _save(fig, path)


def _save(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
