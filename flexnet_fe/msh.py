"""Gmsh files: one gmsh model at a time in this process, and the one reader of ``.msh`` nodes and
cells (the missile mesher, the shell's fin loader and the report's pictures use them).

Base layer: imports nothing of ours. gmsh is initialised once per process and never finalised
here, so modules that keep gmsh initialised are not broken by a finalise.
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import numpy as np

_GMSH_READY = {"done": False}
_SAVED_OPTIONS = ("General.Terminal", "Mesh.MeshSizeMax", "Mesh.MshFileVersion")


@contextmanager
def gmsh_model(name: str):
    """A fresh gmsh model ``name`` in this process's gmsh, removed on exit.

    gmsh is initialised once per process and never finalised here, so other modules that keep
    gmsh initialised (e.g. the shell stage's mesh reader) are not broken by a finalise; the
    global options this module changes are restored on exit.
    """
    import gmsh

    if not _GMSH_READY["done"]:
        gmsh.initialize()  # a second initialise elsewhere only prints a warning (gmsh 4.8)
        _GMSH_READY["done"] = True
    try:
        gmsh.model.add(name)
    except Exception:  # gmsh was finalised by someone else since: initialise again
        gmsh.initialize()
        gmsh.model.add(name)
    saved = {k: gmsh.option.getNumber(k) for k in _SAVED_OPTIONS}
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        yield gmsh
    finally:
        gmsh.model.setCurrent(name)
        gmsh.model.remove()
        for k, v in saved.items():
            gmsh.option.setNumber(k, v)


def read_msh_nodes_and_cells(path: Path, dim: int = 2):
    """Node coordinates [m] (n, 3) and, per gmsh element type of dimension ``dim``, the
    connectivity as 0-based node indices: (x, {element type name: (k, nodes per element)})."""
    with gmsh_model("read") as gmsh:
        gmsh.merge(str(path))
        tags, x, _ = gmsh.model.mesh.getNodes()
        order = np.argsort(tags)
        index = np.empty(int(tags.max()) + 1, np.int64)
        index[tags[order]] = np.arange(tags.size)
        x = np.asarray(x).reshape(-1, 3)
        cells = {}
        types, _, conn = gmsh.model.mesh.getElements(dim)
        for t, c in zip(types, conn):
            name, _, _, nn, _, _ = gmsh.model.mesh.getElementProperties(t)
            cells[name] = index[np.asarray(c, np.int64)].reshape(-1, nn)
    return x, cells
