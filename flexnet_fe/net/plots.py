"""The deployment's one PNG figure: the history laid out like the paper's Fig. 7 (traction) /
Fig. 9 (rotary) — mass speed, rope tension, net area (+ hub spin for the rotary net) — above
the net at eight instants like its Fig. 6 / Fig. 8.

Written for speed (issue 15): one figure and one ``savefig`` per stage, fixed margins (no
``tight_layout``), and the net shapes drawn as images — grey where a pixel holds a node or a
segment midpoint — instead of 20 000 vector lines per panel: at the figure's resolution a pixel
spans about one mesh cell, so the picture is the same (white specks: cells stretched beyond a
pixel), at ~1/10 the cost.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _history_panels(kind: str) -> list[tuple[str, str, str]]:
    """(column, y label, panel title) of the history panels."""
    panels = [("mass_speed_rel_mps", "corner-mass speed [m/s]" if kind == "traction" else "tip-mass speed [m/s]",
               "(a) mass speed (rel. to the net's CoM)"),
              ("max_tension_n", "rope tension [N]", "(b) tension: largest (—), on the masses (--)"),
              ("area_m2", "net area [m²]", "(c) net area (x–y projection, union of cells)")]
    if kind == "rotary":
        panels.append(("hub_spin_radps", "hub spin ω [rad/s]", "(d) hub spin about +z"))
    return panels


def density_image(xy: np.ndarray, springs: np.ndarray, lim: float, bins: int = 220) -> np.ndarray:
    """Rope density of a net projected on x–y: counts of nodes and segment midpoints per pixel
    of a bins × bins grid over [-lim, lim]² [m], shape (bins, bins), rows along y."""
    pts = np.concatenate([xy, 0.5 * (xy[springs[:, 0]] + xy[springs[:, 1]])])
    h, _, _ = np.histogram2d(pts[:, 1], pts[:, 0], bins=bins, range=[[-lim, lim], [-lim, lim]])
    return h


def plot_deployment(path: Path, hist: dict[str, np.ndarray], shapes: list[tuple[float, np.ndarray]],
                    springs: np.ndarray, kind: str, title: str) -> None:
    """Write the figure to ``path``. ``hist`` holds the history columns (``t_s``,
    ``mass_speed_rel_mps``, ``max_tension_n``, ``mass_rope_tension_n``, ``area_m2``,
    ``hub_spin_radps``); ``shapes`` = [(t [s], xy [m] (n, 2)), ...] (up to 8), drawn with the
    segments ``springs`` (m, 2) on the world x–y plane (normal to the flight direction)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = hist["t_s"]
    panels = _history_panels(kind)
    fig = plt.figure(figsize=(12, 8.6))
    top = fig.add_gridspec(1, len(panels), left=0.06, right=0.99, top=0.91, bottom=0.66, wspace=0.32)
    for k, (col, ylabel, sub) in enumerate(panels):
        ax = fig.add_subplot(top[0, k])
        ax.plot(t, hist[col], lw=1.2)
        if col == "max_tension_n":
            ax.plot(t, hist["mass_rope_tension_n"], "--", lw=1.0)
        ax.set_ylabel(ylabel, fontsize=8)
        ax.set_xlabel("time t [s]", fontsize=8)
        ax.set_title(sub, fontsize=8, loc="left")
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    if shapes:
        lim = max(float(np.abs(xy).max()) for _, xy in shapes) * 1.05
        low = fig.add_gridspec(2, 4, left=0.06, right=0.99, top=0.57, bottom=0.05, wspace=0.05, hspace=0.24)
        for k, (ts, xy) in enumerate(shapes[:8]):
            ax = fig.add_subplot(low[k // 4, k % 4])
            ax.imshow(density_image(xy, springs, lim) > 0, origin="lower", extent=(-lim, lim, -lim, lim),
                      cmap="Greys", vmin=0, vmax=1.6, interpolation="nearest")
            ax.set_title(f"t = {ts:.3f} s", fontsize=8)
            ax.tick_params(labelsize=6)
            if k % 4:
                ax.set_yticklabels([])
            else:
                ax.set_ylabel("y [m]", fontsize=8)
            if k >= 4:
                ax.set_xlabel("x [m]", fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.savefig(path, dpi=100)
    plt.close(fig)
