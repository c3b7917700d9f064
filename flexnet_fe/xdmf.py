"""A small reader for the XDMF + HDF5 files dolfinx 0.5.2 writes (``XDMFFile.write_mesh`` then
``write_function`` per output time), with h5py.

Why not VTK's ``vtkXdmfReader`` (``pyvista.XdmfReader``): it crashes the process (SIGSEGV)
when the ``.h5`` file next to the ``.xdmf`` is missing or truncated, which is exactly what a
killed run can leave; a report must say "unreadable" instead. Only what dolfinx writes is
read: one ``Uniform`` mesh grid (HDF data items), then one ``Temporal`` collection per function
whose grids each hold a ``Time`` and one ``Attribute``. Anything else is a :class:`FlexnetError`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexnet_fe.errors import FlexnetError

CELL_TYPES = {"Triangle": 3, "Quadrilateral": 4}
"""XDMF topology types read, with their nodes per cell (XDMF/VTK node order, as dolfinx writes)."""


@dataclass(frozen=True)
class XdmfMesh:
    """points [m], shape (n, 3) (z = 0 added for 2-D geometry); cells, shape (m, k); cell type."""

    points: np.ndarray
    cells: np.ndarray
    cell_type: str


@dataclass(frozen=True)
class XdmfField:
    """One function's time series: center ``Cell`` or ``Node``, times [s] (increasing) and the
    ``file.h5:/dataset`` reference of each time."""

    name: str
    center: str
    times: tuple[float, ...]
    refs: tuple[str, ...]


def _root(path: Path) -> ET.Element:
    path = Path(path)
    if not path.is_file():
        raise FlexnetError(f"{path}: no such file")
    try:
        return ET.parse(path).getroot()
    except (OSError, ET.ParseError) as err:
        raise FlexnetError(f"{path}: not an XDMF file ({err})") from None


def _ref(path: Path, item: ET.Element | None, what: str) -> str:
    if item is None or item.text is None:
        raise FlexnetError(f"{path}: {what} has no data item")
    if item.get("Format") != "HDF":
        raise FlexnetError(f"{path}: {what} is stored as {item.get('Format')!r}; only HDF is read")
    return item.text.strip()


def _load(path: Path, ref: str) -> np.ndarray:
    import h5py

    file, _, dataset = ref.partition(":")
    h5 = Path(path).parent / file
    try:
        with h5py.File(h5, "r") as f:
            return np.asarray(f[dataset][()])
    except (OSError, KeyError) as err:
        raise FlexnetError(f"{path}: cannot read {ref} ({err})") from None


def read_mesh(path: Path) -> XdmfMesh:
    """The mesh of the first ``Uniform`` grid that has a Topology and a Geometry."""
    root = _root(path)
    for grid in root.iter("Grid"):
        topo, geom = grid.find("Topology"), grid.find("Geometry")
        if grid.get("GridType") == "Uniform" and topo is not None and geom is not None:
            break
    else:
        raise FlexnetError(f"{path}: no mesh grid")
    ctype = topo.get("TopologyType")
    if ctype not in CELL_TYPES:
        raise FlexnetError(f"{path}: topology {ctype!r} not supported ({', '.join(CELL_TYPES)})")
    cells = _load(path, _ref(path, topo.find("DataItem"), "Topology")).astype(np.int64)
    x = _load(path, _ref(path, geom.find("DataItem"), "Geometry")).astype(np.float64)
    if cells.ndim != 2 or cells.shape[1] != CELL_TYPES[ctype] or x.ndim != 2 or x.shape[1] not in (2, 3):
        raise FlexnetError(f"{path}: topology {cells.shape} / geometry {x.shape} do not fit {ctype}")
    if cells.size and (cells.min() < 0 or cells.max() >= len(x)):
        raise FlexnetError(f"{path}: topology refers to missing points")
    points = np.column_stack([x, np.zeros(len(x))]) if x.shape[1] == 2 else x
    return XdmfMesh(points=points, cells=cells, cell_type=ctype)


def list_fields(path: Path) -> dict[str, XdmfField]:
    """Every function time series of the file, by name."""
    root = _root(path)
    out: dict[str, XdmfField] = {}
    for coll in root.iter("Grid"):
        if coll.get("GridType") != "Collection":
            continue
        steps: dict[str, list] = {}
        for grid in coll.findall("Grid"):
            time = grid.find("Time")
            for att in grid.findall("Attribute"):
                name = att.get("Name", "")
                t = float(time.get("Value")) if time is not None else float("nan")
                steps.setdefault(name, []).append((t, att.get("Center", ""),
                                                   _ref(path, att.find("DataItem"), f"attribute {name}")))
        for name, s in steps.items():
            s.sort(key=lambda e: e[0])
            out[name] = XdmfField(name=name, center=s[0][1], times=tuple(e[0] for e in s),
                                  refs=tuple(e[2] for e in s))
    return out


def nearest_time_index(times: tuple[float, ...], time_s: float | None) -> int:
    """Index of the output time nearest ``time_s`` (the last when ``None``)."""
    if not times:
        raise FlexnetError("the field has no output time")
    if time_s is None:
        return len(times) - 1
    return int(np.argmin(np.abs(np.asarray(times) - time_s)))


def read_field(path: Path, field: XdmfField, index: int) -> np.ndarray:
    """Values of ``field`` at output ``index``: (n,) for scalars, (n, c) for vectors."""
    v = _load(path, field.refs[index]).astype(np.float64)
    return v[:, 0] if v.ndim == 2 and v.shape[1] == 1 else v
