"""Pictures of the physics for the report (issue 12 item 2), rendered offscreen with PyVista.

- :func:`render_missile_stress`: the whole missile (body + every solved fin) in one 3-D view,
  two panels: the envelope (peak over time per cell) and the field at the time of the largest
  peak (warped ×:data:`WARP`), coloured by von Mises stress [MPa] on a scale that ends at the
  allowable (cells above it drawn magenta), each fin's peak location marked and labelled.
- :func:`render_net_events`: the net and the missile at first contact, mid-passage and exit
  (nearest collide snapshots), side view, the camera on the missile.
- :func:`render_animation`: every collide snapshot as one GIF frame (imageio), fixed camera.

All run in the report's child process (:func:`flexnet_fe.report.pictures.render_isolated`):
VTK crashes after ``dolfinx.cpp`` is imported (DESIGN.md §2). Inputs are the report's merged
missile files (:mod:`flexnet_fe.report.paraview`) and the collide stage's ``.pvd`` snapshots
(world frame W: net initially in the x–y plane, missile flying along +z).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from flexnet_fe.errors import FlexnetError
from flexnet_fe.report.units import PA_TO_MPA, S_TO_MS

WARP = 50.0
"""Displacement magnification of the at-peak missile picture (fin deflections are mm)."""

ABOVE_COLOUR = "magenta"
"""Colour of cells whose stress exceeds the end of the colour scale (the allowable on the missile,
the structural peak on a fin's envelope)."""

NET_CROP_M = 2.0
"""Half-width [m] of the box around the missile path in which net segments are drawn."""


def _blocks(multiblock):
    """(name without VTK's '[k]' suffix, block) of a MultiBlock."""
    out = []
    for k in range(multiblock.n_blocks):
        block = multiblock[k]
        if block is not None and block.n_cells:
            out.append((multiblock.get_block_name(k).split("[")[0], block))
    return out


def _read_xdmf(path: Path, time_s: float | None):
    import pyvista as pv

    if not Path(path).is_file() or not Path(path).with_suffix(".h5").is_file():
        raise FlexnetError(f"{path}: missing (or its .h5 is)")
    reader = pv.XdmfReader(str(path))
    times = reader.time_values
    t = times[int(np.argmin(np.abs(np.asarray(times) - time_s)))] if time_s is not None and times else None
    if t is not None:
        reader.set_active_time_value(t)
    return _blocks(reader.read()), t


def _missile_panel(pl, blocks, field: str, allowable_pa: float | None, vmax_pa: float, warp: float,
                   marks: list[dict]) -> float:
    """Draw one panel; returns the largest value of ``field`` shown [Pa]."""
    import pyvista as pv

    clim = [0.0, (allowable_pa if allowable_pa is not None else vmax_pa) * PA_TO_MPA]
    shown = 0.0
    bar = "MPa"
    first = True
    for name, block in blocks:
        mesh = block
        if warp and "displacement_m" in block.point_data:
            mesh = block.warp_by_vector("displacement_m", factor=warp)
        if field in block.cell_data:
            mesh = mesh.copy()
            values = np.asarray(block.cell_data[field])
            shown = max(shown, float(np.nanmax(values, initial=0.0)))
            mesh.cell_data["σ [MPa]"] = values * PA_TO_MPA
            pl.add_mesh(mesh, scalars="σ [MPa]", cmap="turbo", clim=clim,
                        above_color=ABOVE_COLOUR if allowable_pa else None, show_edges=False,
                        show_scalar_bar=first, scalar_bar_args={"title": bar, "fmt": "%.0f", "vertical": True,
                                                                "position_x": 0.86, "position_y": 0.1,
                                                                "width": 0.06, "height": 0.7,
                                                                "title_font_size": 14, "label_font_size": 12})
            first = False
        else:
            pl.add_mesh(mesh, color="lightgrey", opacity=1.0, smooth_shading=True)
    if marks:
        pts = np.array([m["location_m"] for m in marks], dtype=float)
        labels = [f"{m['name']} {m['value_pa'] * PA_TO_MPA:.0f} MPa" for m in marks]
        pl.add_point_labels(pv.PolyData(pts), labels, point_size=14, point_color="black",
                            font_size=11, shape_opacity=0.6, always_visible=True)
    return shown


def _oblique_camera(pl, bounds) -> None:
    b = np.asarray(bounds).reshape(3, 2)
    centre = b.mean(axis=1)
    size = float(np.linalg.norm(b[:, 1] - b[:, 0]))
    direction = np.array([0.45, -0.45, 1.0])  # mostly from above: the y-fins face-on
    pl.camera_position = [tuple(centre + 1.6 * size * direction / np.linalg.norm(direction)),
                          tuple(centre), (0.0, 0.0, 1.0)]
    pl.reset_camera()
    pl.camera.zoom(1.25)


def render_missile_stress(missile_xdmf: str, envelope_xdmf: str, png: str, time_s: float | None,
                          allowable_pa: float | None, marks: list[dict], title: str = "",
                          peak_label: str = "") -> dict:
    """The two-panel whole-missile stress picture (module doc). ``marks``: per fin
    ``{name, location_m [m] (3,), value_pa}`` (the summary's peaks). Returns
    ``{"envelope_max_pa", "frame_max_pa", "frame_time_s"}``."""
    import pyvista as pv

    env_blocks, _ = _read_xdmf(Path(envelope_xdmf), None)
    frame_blocks, t = _read_xdmf(Path(missile_xdmf), time_s)
    vmax = max(float(np.nanmax(b.cell_data["peak_von_mises_pa"])) for _, b in env_blocks
               if "peak_von_mises_pa" in b.cell_data)
    pl = pv.Plotter(off_screen=True, shape=(1, 2), window_size=[1700, 800], border=False)
    try:
        pl.subplot(0, 0)
        env_max = _missile_panel(pl, env_blocks, "peak_von_mises_pa", allowable_pa, vmax, 0.0, marks)
        allow_txt = (f"\nallowable {allowable_pa * PA_TO_MPA:.4g} MPa = top of the scale; magenta cells exceed it"
                     if allowable_pa else "")
        pl.add_text(f"{title}\nEnvelope: peak over time of the cell von Mises stress\n"
                    f"max {env_max * PA_TO_MPA:.4g} MPa; undeformed; frame B{allow_txt}",
                    font_size=10, position="upper_left")
        pl.add_axes()
        _oblique_camera(pl, pv.MultiBlock([b for _, b in env_blocks]).bounds)
        pl.subplot(0, 1)
        frame_max = _missile_panel(pl, frame_blocks, "von_mises_pa", allowable_pa, vmax, WARP,
                                   [m for m in marks if m.get("at_frame")])
        t_txt = f"t = {t * S_TO_MS:.4g} ms" if t is not None else "last output"
        pl.add_text(f"Output nearest the largest peak ({peak_label}): {t_txt}\n"
                    f"von Mises (max over top/mid/bottom); max {frame_max * PA_TO_MPA:.4g} MPa\n"
                    f"displacement ×{WARP:g}",
                    font_size=10, position="upper_left")
        pl.add_axes()
        _oblique_camera(pl, pv.MultiBlock([b for _, b in frame_blocks]).bounds)
        Path(png).parent.mkdir(parents=True, exist_ok=True)
        pl.screenshot(str(png))
    finally:
        pl.close()
    return {"envelope_max_pa": env_max, "frame_max_pa": frame_max, "frame_time_s": t}


def _pvd_nearest(pvd: Path, t: float):
    import pyvista as pv

    from flexnet_fe.io import pvd_entries

    entries = [e for e in pvd_entries(pvd) if e[1].is_file()]
    if not entries:
        raise FlexnetError(f"{pvd}: no snapshot files found")
    k = int(np.argmin([abs(e[0] - t) for e in entries]))
    return entries[k][0], pv.read(str(entries[k][1]))


def _side_camera(pl, centre: np.ndarray, flight: np.ndarray, scale: float) -> None:
    """Parallel projection, looking at ``centre`` from the side of the flight direction."""
    side = np.cross(flight, [1.0, 0.0, 0.0])
    if np.linalg.norm(side) < 1e-6:
        side = np.cross(flight, [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    eye = side + 0.35 * np.cross(flight, side) + 0.2 * flight
    eye /= np.linalg.norm(eye)
    pl.enable_parallel_projection()
    pl.camera_position = [tuple(centre + 20.0 * eye), tuple(centre), tuple(flight)]
    pl.camera.parallel_scale = scale


def _flight(missile_pvd: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(first centre, last centre, unit flight direction) of the missile snapshots [m]."""
    import pyvista as pv

    from flexnet_fe.io import pvd_entries

    entries = [e for e in pvd_entries(missile_pvd) if e[1].is_file()]
    if len(entries) < 2:
        raise FlexnetError(f"{missile_pvd}: fewer than two missile snapshots")
    a = np.asarray(pv.read(str(entries[0][1])).center)
    b = np.asarray(pv.read(str(entries[-1][1])).center)
    d = b - a
    n = float(np.linalg.norm(d))
    return a, b, (d / n if n > 0 else np.array([0.0, 0.0, 1.0]))


def _net_near(net, box_centre: np.ndarray, half: np.ndarray):
    lo, hi = box_centre - half, box_centre + half
    return net.clip_box([lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]], invert=False)


def render_net_events(net_pvd: str, missile_pvd: str, png: str, events: list[list]) -> list[float]:
    """Net + missile at each ``events`` entry ``[label, time [s]]`` (nearest snapshots), side
    view centred on the missile, net cropped to :data:`NET_CROP_M` around it, coloured by rope
    tension [N] (one range for all panels). Returns the snapshot times shown [s]."""
    import pyvista as pv

    _, _, flight = _flight(Path(missile_pvd))
    frames = []
    for label, t in events:
        tn, net = _pvd_nearest(Path(net_pvd), float(t))
        _, mis = _pvd_nearest(Path(missile_pvd), float(t))
        centre = np.asarray(mis.center)
        length = float(np.ptp(np.asarray(mis.points) @ flight))
        half = np.full(3, NET_CROP_M) + np.abs(flight) * 0.5 * length
        frames.append((label, tn, _net_near(net, centre, half), mis, centre, length))
    tmax = max((float(np.max(f[2].cell_data["tension_n"])) for f in frames
                if f[2].n_cells and "tension_n" in f[2].cell_data), default=0.0)
    pl = pv.Plotter(off_screen=True, shape=(1, len(frames)), window_size=[600 * len(frames), 700], border=False)
    try:
        for k, (label, tn, net, mis, centre, length) in enumerate(frames):
            pl.subplot(0, k)
            if net.n_cells:
                colour = "tension_n" in net.cell_data and tmax > 0
                pl.add_mesh(net, scalars="tension_n" if colour else None, color=None if colour else "black",
                            cmap="viridis", clim=[0.0, tmax] if colour else None, line_width=1.5,
                            show_scalar_bar=colour and k == len(frames) - 1,
                            scalar_bar_args={"title": "rope tension [N]", "fmt": "%.3g", "vertical": True,
                                             "position_x": 0.82, "position_y": 0.25, "height": 0.5})
            pl.add_mesh(mis, color="black", line_width=2.0)
            pl.add_text(f"{label}\nt = {tn * S_TO_MS:.4g} ms", font_size=11)
            _side_camera(pl, centre, flight, 0.6 * length + NET_CROP_M * 0.5)
        pl.screenshot(str(png))
    finally:
        pl.close()
    return [f[1] for f in frames]


def render_animation(net_pvd: str, missile_pvd: str, gif: str, fps: float = 6.0) -> int:
    """Every collide snapshot as a GIF frame: net (cropped around the missile path, coloured by
    rope tension [N], fixed range) and missile, fixed side camera covering the whole path.
    Returns the number of frames."""
    import imageio.v2 as imageio
    import pyvista as pv

    from flexnet_fe.io import pvd_entries

    nets = [e for e in pvd_entries(Path(net_pvd)) if e[1].is_file()]
    mis = {round(t, 12): f for t, f in pvd_entries(Path(missile_pvd)) if f.is_file()}
    if not nets or not mis:
        raise FlexnetError(f"{net_pvd}: no snapshots to animate")
    a, b, flight = _flight(Path(missile_pvd))
    centre = 0.5 * (a + b)
    first = pv.read(str(next(iter(mis.values()))))
    length = float(np.ptp(np.asarray(first.points) @ flight))
    path_len = float(np.linalg.norm(b - a))
    half = np.full(3, NET_CROP_M) + np.abs(flight) * 0.5 * (path_len + length)
    meshes = [(t, _net_near(pv.read(str(f)), centre, half)) for t, f in nets]
    tmax = max((float(np.max(m.cell_data["tension_n"])) for _, m in meshes
                if m.n_cells and "tension_n" in m.cell_data), default=0.0)
    frames = []
    pl = pv.Plotter(off_screen=True, window_size=[900, 700])   # one window, meshes replaced by name
    try:
        for t, net in meshes:
            key = min(mis, key=lambda s: abs(s - t))
            if net.n_cells:
                colour = "tension_n" in net.cell_data and tmax > 0
                pl.add_mesh(net, scalars="tension_n" if colour else None, color=None if colour else "black",
                            cmap="viridis", clim=[0.0, tmax] if colour else None, line_width=1.5, name="net",
                            scalar_bar_args={"title": "rope tension [N]", "fmt": "%.3g"})
            else:
                pl.remove_actor("net")
            pl.add_mesh(pv.read(str(mis[key])), color="black", line_width=2.0, name="missile")
            pl.add_text(f"collision, t = {t * S_TO_MS:.3f} ms", font_size=12, name="time")
            _side_camera(pl, centre, flight, 0.4 * (path_len + length) + 0.5)
            frames.append(pl.screenshot(return_img=True))
    finally:
        pl.close()
    Path(gif).parent.mkdir(parents=True, exist_ok=True)
    imageio.mimsave(gif, frames, duration=1000.0 / fps, loop=0)
    return len(frames)
