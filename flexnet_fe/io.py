"""Small file helpers shared by the stages: atomic JSON, float64 CSV histories.

Results are never pickled: JSON, CSV, ``.npz`` (``allow_pickle=False``), XDMF/HDF5, VTK.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from flexnet_fe.errors import FlexnetError


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _current_umask()


def _default(o: Any):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (temp file in the same folder + rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, 0o666 & ~_UMASK)  # mkstemp makes 0600; give the file the usual mode
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write_json(path: Path, obj: Any) -> None:
    """Write ``obj`` as indented JSON atomically; numpy scalars/arrays are converted."""
    atomic_write_text(path, json.dumps(obj, indent=2, default=_default, allow_nan=False) + "\n")


def read_json(path: Path) -> Any:
    return json.loads(Path(path).read_text())


def write_history_csv(path: Path, columns: Mapping[str, np.ndarray]) -> None:
    """Write equal-length 1-D columns as CSV (float64, 17 significant digits, header row).

    Column names carry their unit, e.g. ``t_s``, ``area_m2``, ``max_tension_n``.
    """
    names = list(columns)
    data = np.column_stack([np.asarray(columns[n], dtype=np.float64).ravel() for n in names])
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    np.savetxt(tmp, data, delimiter=",", header=",".join(names), comments="", fmt="%.17g")
    os.replace(tmp, path)


def read_history_csv(path: Path) -> dict[str, np.ndarray]:
    """Read a CSV written by :func:`write_history_csv` into ``{name: float64 array}``."""
    arr = np.genfromtxt(path, delimiter=",", names=True, dtype=np.float64)
    return {n: np.atleast_1d(arr[n]) for n in arr.dtype.names}


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
