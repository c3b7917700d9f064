"""PNG plots of a deployment history, laid out like the paper's Fig. 7 (traction) and
Fig. 9 (rotary): mass speed, rope tension, net area (+ hub spin for the rotary net)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def plot_history(path: Path, hist: dict[str, np.ndarray], kind: str, title: str) -> None:
    """Write the figure to ``path``. ``hist`` holds the history columns (``t_s``,
    ``mass_speed_rel_mps``, ``max_tension_n``, ``mass_rope_tension_n``, ``area_m2``,
    ``hub_spin_radps``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = hist["t_s"]
    panels = [("mass_speed_rel_mps", "corner-mass speed [m/s]" if kind == "traction" else "tip-mass speed [m/s]",
               "(a) speed of the masses (relative to the net's centre of mass)"),
              ("max_tension_n", "rope tension [N]", "(b) rope tension: largest in the net (—), mean of the ropes on the masses (--)"),
              ("area_m2", "net area [m²]", "(c) net area (projection on x–y, union of cells)")]
    if kind == "rotary":
        panels.append(("hub_spin_radps", "hub spin ω [rad/s]", "(d) hub spin about +z"))
    fig, axes = plt.subplots(len(panels), 1, figsize=(7, 2.4 * len(panels)), sharex=True)
    for ax, (col, ylabel, sub) in zip(axes, panels):
        ax.plot(t, hist[col], lw=1.2)
        if col == "max_tension_n":
            ax.plot(t, hist["mass_rope_tension_n"], "--", lw=1.0)
        ax.set_ylabel(ylabel)
        ax.set_title(sub, fontsize=9, loc="left")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time t [s]")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_shapes(path: Path, shapes: list[tuple[float, np.ndarray]], springs: np.ndarray, title: str) -> None:
    """Net outlines at several instants (like the paper's Fig. 6 / Fig. 8): each panel shows
    the segments projected on the world x–y plane (the plane normal to the flight direction).
    ``shapes`` = [(t [s], xy [m] (n, 2)), ...]."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    ncol = 4
    nrow = -(-len(shapes) // ncol)
    lim = max(float(np.abs(xy).max()) for _, xy in shapes) * 1.05
    fig, axes = plt.subplots(nrow, ncol, figsize=(3 * ncol, 3 * nrow), squeeze=False)
    for ax in axes.ravel():
        ax.set_visible(False)
    for ax, (t, xy) in zip(axes.ravel(), shapes):
        ax.set_visible(True)
        ax.add_collection(LineCollection(xy[springs], linewidths=0.2, colors="k", rasterized=True))
        ax.set_xlim(-lim, lim); ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.set_title(f"t = {t:.3f} s", fontsize=9)
        ax.tick_params(labelsize=7)
    axes[0, 0].set_ylabel("y [m]"); axes[-1, 0].set_xlabel("x [m]")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
