"""Offscreen PyVista picture of a missile (body surface mesh + fin shell meshes), body frame B.

Rendering without a display uses EGL: the environment variables
``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow`` and ``PYVISTA_OFF_SCREEN=true`` are set before
PyVista is imported (DESIGN.md §2).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from flexnet_fe.msh import read_msh_nodes_and_cells

_VTK_QUAD, _VTK_TRIANGLE = 9, 5


def _grid(path: Path):
    import pyvista as pv

    x, cells = read_msh_nodes_and_cells(path)
    blocks, types = [], []
    for name, conn in cells.items():
        vtk_type = _VTK_QUAD if name.startswith("Quadrilateral") else _VTK_TRIANGLE
        blocks.append(np.hstack([np.full((conn.shape[0], 1), conn.shape[1]), conn]).ravel())
        types.append(np.full(conn.shape[0], vtk_type, np.uint8))
    return pv.UnstructuredGrid(np.concatenate(blocks), np.concatenate(types), x)


def render_missile_png(mesh_paths: dict[str, Path], png: Path, title: str,
                       window_size: tuple[int, int] = (1400, 700)) -> Path:
    """Render the meshes written by :func:`flexnet_fe.missile.mesh.write_meshes` into ``png``.

    Body grey, wings blue, rudders orange, element edges shown on the fins; axes are body axes B.
    """
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
    import pyvista as pv

    png = Path(png)
    png.parent.mkdir(parents=True, exist_ok=True)
    plotter = pv.Plotter(off_screen=True, window_size=list(window_size))
    for name, path in mesh_paths.items():
        grid = _grid(path)
        if name == "body":
            plotter.add_mesh(grid, color="lightgrey", smooth_shading=True)
        else:
            color = "royalblue" if name.startswith("wing") else "darkorange"
            plotter.add_mesh(grid, color=color, show_edges=True, edge_color="black",
                             line_width=0.5)
    plotter.add_text(f"{title}  (body frame B: x_b forward, y_b up, z_b)", font_size=12)
    plotter.add_axes(xlabel="x_b", ylabel="y_b", zlabel="z_b")
    x_min, x_max = plotter.bounds[0], plotter.bounds[1]
    focal = (0.5 * (x_min + x_max), 0.0, 0.0)
    length = x_max - x_min
    # seen from ahead-right and above; +y_b up on the picture
    position = (focal[0] + 0.45 * length, 0.35 * length, 0.75 * length)
    plotter.camera_position = [position, focal, (0.0, 1.0, 0.0)]
    plotter.reset_camera()
    plotter.camera.zoom(1.5)
    plotter.screenshot(str(png))
    plotter.close()
    return png
