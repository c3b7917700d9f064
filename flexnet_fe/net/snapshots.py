"""Net snapshots as a line-mesh time series: one ``.vtu`` per snapshot plus a ``.pvd``
collection (opens in ParaView and in PyVista with ``pyvista.read(path_to_pvd)``)."""

from __future__ import annotations

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from flexnet_fe.io import atomic_write_text


def write_vtu(path: Path, x: np.ndarray, v: np.ndarray, springs: np.ndarray, tension: np.ndarray) -> None:
    """One snapshot: points x [m] (n, 3) in the world frame W, lines ``springs`` (m, 2);
    point data velocity [m/s] and speed; cell data tension [N].

    VTK XML UnstructuredGrid, data appended raw (uncompressed, little-endian, UInt64 block
    headers), written directly with numpy: ~1 ms for the 20 200-segment net against ~70 ms
    through pyvista/VTK's writer (which also compresses); read back by ParaView and
    ``pyvista.read``."""
    n, m = len(x), len(springs)
    arrays = [  # (section, attributes, data)
        ("PointData", 'type="Float64" Name="velocity_mps" NumberOfComponents="3"', np.asarray(v, dtype="<f8")),
        ("PointData", 'type="Float64" Name="speed_mps"', np.sqrt(np.einsum("ij,ij->i", v, v)).astype("<f8")),
        ("CellData", 'type="Float64" Name="tension_n"', np.asarray(tension, dtype="<f8")),
        ("Points", 'type="Float64" Name="Points" NumberOfComponents="3"', np.asarray(x, dtype="<f8")),
        ("Cells", 'type="Int64" Name="connectivity"', np.asarray(springs, dtype="<i8")),
        ("Cells", 'type="Int64" Name="offsets"', np.arange(2, 2 * m + 1, 2, dtype="<i8")),
        ("Cells", 'type="UInt8" Name="types"', np.full(m, 3, dtype=np.uint8)),  # VTK_LINE
    ]
    xml, offset = {}, 0
    for section, attrs, data in arrays:
        xml.setdefault(section, []).append(f'<DataArray {attrs} format="appended" offset="{offset}"/>')
        offset += 8 + data.nbytes
    head = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
            f'header_type="UInt64">\n<UnstructuredGrid>\n<Piece NumberOfPoints="{n}" NumberOfCells="{m}">\n'
            + "".join(f"<{sec}>{''.join(xml[sec])}</{sec}>\n" for sec in ("PointData", "CellData", "Points", "Cells"))
            + '</Piece>\n</UnstructuredGrid>\n<AppendedData encoding="raw">\n_')
    with open(path, "wb") as fh:
        fh.write(head.encode())
        for _, _, data in arrays:
            fh.write(np.uint64(data.nbytes).tobytes())
            fh.write(np.ascontiguousarray(data).tobytes())
        fh.write(b"\n</AppendedData>\n</VTKFile>\n")


def write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """ParaView collection of (time [s], relative .vtu file name)."""
    rows = "\n".join(f'    <DataSet timestep="{t:.9g}" part="0" file={quoteattr(f)}/>' for t, f in entries)
    atomic_write_text(Path(path), (
        '<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
        f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n"))
