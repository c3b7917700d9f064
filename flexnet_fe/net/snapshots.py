"""Net snapshots as a line-mesh time series: one ``.vtu`` per snapshot plus a ``.pvd``
collection (opens in ParaView and in PyVista with ``pyvista.read(path_to_pvd)``)."""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from flexnet_fe.errors import FlexnetError
from flexnet_fe.io import atomic_write_text


def write_vtu(path: Path, x: np.ndarray, v: np.ndarray, springs: np.ndarray, tension: np.ndarray) -> None:
    """One snapshot: points x [m] (n, 3) in the world frame W, lines ``springs`` (m, 2);
    point data velocity [m/s] and speed; cell data tension [N]."""
    import pyvista as pv

    cells = np.hstack([np.full((len(springs), 1), 2, dtype=np.int64), springs]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(len(springs), pv.CellType.LINE, dtype=np.uint8),
                               np.ascontiguousarray(x, dtype=np.float64))
    grid.point_data["velocity_mps"] = v
    grid.point_data["speed_mps"] = np.linalg.norm(v, axis=1)
    grid.cell_data["tension_n"] = tension
    grid.save(str(path), binary=True)


def write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """ParaView collection of (time [s], relative .vtu file name)."""
    rows = "\n".join(f'    <DataSet timestep="{t:.9g}" part="0" file={quoteattr(f)}/>' for t, f in entries)
    atomic_write_text(Path(path), (
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
        f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n"))


def pvd_entries(pvd: Path) -> list[tuple[float, Path]]:
    """(time [s], data file) of every dataset of a ParaView ``.pvd`` collection, by time."""
    import xml.etree.ElementTree as ET

    pvd = Path(pvd)
    try:
        root = ET.parse(pvd).getroot()
    except (OSError, ET.ParseError) as err:
        raise FlexnetError(f"{pvd}: cannot read the collection ({err})") from None
    out = [(float(ds.get("timestep", "nan")), pvd.parent / ds.get("file", ""))
           for ds in root.iter("DataSet")]
    return sorted(out, key=lambda e: e[0])
