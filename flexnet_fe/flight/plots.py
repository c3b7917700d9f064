"""Plots like the paper's Fig. 19–22 (matplotlib, Agg). Frames: positions in the case frame P."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from flexnet_fe.flight.config import FlightConfig  # noqa: E402

G0 = 9.80665


def plot_engagement(h: dict[str, np.ndarray], flight: FlightConfig, out_dir: Path) -> list[Path]:
    """Trajectories (3-D), commanded vs achieved acceleration, Euler angles, fin deflections."""
    out_dir = Path(out_dir)
    paths = []
    t = h["t_s"]
    up = flight.vertical_axis.value
    # Fig. 19/20: trajectories
    fig = plt.figure(figsize=(7, 5.5))
    ax = fig.add_subplot(projection="3d")
    ax.plot(h["missile_x_m"], h["missile_z_m"] if up == "y" else h["missile_y_m"],
            h["missile_y_m"] if up == "y" else h["missile_z_m"], label="missile")
    ax.plot(h["target_x_m"], h["target_z_m"] if up == "y" else h["target_y_m"],
            h["target_y_m"] if up == "y" else h["target_z_m"], label="aircraft")
    ax.set_xlabel("x [m]")
    ax.set_ylabel(("z" if up == "y" else "y") + " [m]")
    ax.set_zlabel(f"{up} (up) [m]")
    ax.set_title("Trajectories (case frame)")
    ax.legend()
    paths.append(out_dir / "flight_trajectory.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)
    # Fig. 21 (a)(b) / 22 (b): commanded vs achieved acceleration (body axes)
    fig, axs = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for a, c, m, name in ((axs[0], "accel_cmd_y_mps2", "accel_y_mps2", "y_b (pitch)"),
                          (axs[1], "accel_cmd_z_mps2", "accel_z_mps2", "z_b (yaw)")):
        a.plot(t, h[c] / G0, "--", label="command")
        a.plot(t, h[m] / G0, label="achieved")
        a.set_ylabel(f"{name} load [g]")
        a.grid(True)
        a.legend()
    axs[1].set_xlabel("t [s]")
    fig.suptitle("Commanded vs achieved normal load (body axes, specific force)")
    paths.append(out_dir / "flight_load.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)
    # Fig. 21 (c)(d)(e): attitude
    fig, axs = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
    for a, k, name in zip(axs, ("yaw_rad", "pitch_rad", "roll_rad"), ("yaw ψ", "pitch θ", "roll φ")):
        a.plot(t, np.degrees(h[k]))
        a.set_ylabel(f"{name} [deg]")
        a.grid(True)
    axs[-1].set_xlabel("t [s]")
    fig.suptitle("Missile attitude (Euler y-z-x, flight frame)")
    paths.append(out_dir / "flight_attitude.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)
    # fin deflections against limits
    fig, ax = plt.subplots(figsize=(7, 4))
    lim = flight.actuator.max_deflection_deg
    for i in range(4):
        ax.plot(t, np.degrees(h[f"fin{i}_rad"]), label=f"fin {i}")
    ax.axhline(lim, color="k", ls=":", label="limit")
    ax.axhline(-lim, color="k", ls=":")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("fin deflection [deg]")
    ax.grid(True)
    ax.legend(ncol=5, fontsize=8)
    paths.append(out_dir / "flight_fins.png")
    fig.savefig(paths[-1], dpi=120)
    plt.close(fig)
    return paths


def plot_sweep(cols: dict[str, list[float]], parameter: str, lethal_radius: float, out_dir: Path) -> Path:
    """Miss distance vs swept damage parameter (log scale; ∞ = diverged / no closest approach)."""
    fig, ax = plt.subplots(figsize=(7, 4))
    x = np.asarray(cols["value"])
    for k, v in cols.items():
        if k == "value":
            continue
        y = np.asarray(v, dtype=float)
        fin = np.isfinite(y)
        ax.semilogy(x[fin], np.maximum(y[fin], 1e-3), "o-", label=k.replace("miss_m_", "").replace("miss_m", "miss"))
        if (~fin).any():
            ax.plot(x[~fin], np.full((~fin).sum(), 1e4), "x", color="r", label=f"{k}: diverged")
    ax.axhline(lethal_radius, color="k", ls=":", label="lethal radius")
    ax.set_xlabel(parameter.replace("_", " ") + " [-]")
    ax.set_ylabel("miss distance [m]")
    ax.grid(True, which="both")
    ax.legend(fontsize=8)
    path = Path(out_dir) / "flight_miss_vs_damage.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path
