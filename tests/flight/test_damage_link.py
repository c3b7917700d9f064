"""Shell → flight link: overstressed fin area from dolfinx XDMF envelopes (as the shell stage writes them)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from flexnet_fe.flight.config import FlightConfig
from flexnet_fe.flight.damage import damage_from_shell, read_cell_field

dolfinx = pytest.importorskip("dolfinx")


def _write_envelope(path, cell_type, nx, ny, values_of_midpoint):
    """A flat 2 m × 1 m 'fin' with a DG0 peak_von_mises_pa field, written like the shell stage."""
    from dolfinx import fem, mesh
    from dolfinx.io import XDMFFile
    from mpi4py import MPI

    path.parent.mkdir(parents=True, exist_ok=True)
    m = mesh.create_rectangle(MPI.COMM_SELF, [np.array([0.0, 0.0]), np.array([2.0, 1.0])], [nx, ny], cell_type)
    v0 = fem.FunctionSpace(m, ("DG", 0))
    fn = fem.Function(v0, name="peak_von_mises_pa")
    x = v0.tabulate_dof_coordinates()
    fn.x.array[:] = values_of_midpoint(x[:, 0], x[:, 1])
    with XDMFFile(MPI.COMM_SELF, str(path), "w") as f:
        f.write_mesh(m)
        f.write_function(fn, 0.0)


@pytest.mark.parametrize("cell_type", ["quadrilateral", "triangle"])
def test_overstressed_area_share_is_exact_geometry(tmp_path, cell_type):
    from dolfinx.mesh import CellType

    # stress 600 MPa on cells whose centre has x < 0.5 (a quarter of the 2 m × 1 m plate), 100 MPa elsewhere
    env = tmp_path / "wing_1" / "envelope.xdmf"
    _write_envelope(env, getattr(CellType, cell_type), 8, 4, lambda x, y: np.where(x < 0.5, 600e6, 100e6))
    areas, values = read_cell_field(env)
    # Reference: plate area 2 m², overstressed strip 0.5 m × 1 m (cell edges fall on x = 0.5).
    assert areas.sum() == pytest.approx(2.0, rel=1e-12)
    assert areas[values > 503e6].sum() == pytest.approx(0.5, rel=1e-12)


def test_damage_fractions_and_stage_use_them(tmp_path):
    from dolfinx.mesh import CellType

    shell = tmp_path / "shell"
    _write_envelope(shell / "wing_1" / "envelope.xdmf", CellType.quadrilateral, 4, 2,
                    lambda x, y: np.where(x < 1.0, 600e6, 1e6))          # half of wing_1 overstressed
    _write_envelope(shell / "rudder_2" / "envelope.xdmf", CellType.quadrilateral, 4, 2,
                    lambda x, y: np.full_like(x, 900e6))                  # rudder_2 entirely
    d = damage_from_shell(shell, 503e6)
    # wings: (0.5 + 0 + 0 + 0)/4; rudders: 1 − (1 + 0 + 0 + 0)/4
    assert d.per_fin == {"rudder_2": pytest.approx(1.0), "wing_1": pytest.approx(0.5)}
    assert d.wing_damage == pytest.approx(0.125) and d.rudder_effectiveness == pytest.approx(0.75)
    flight = FlightConfig(dt=2e-4, output_dt=2e-3, damage_from_shell=True, damage_allowable_stress=503e6)
    summary = run_flight_in(tmp_path / "flight", flight, shell)
    assert summary["wing_damage"] == pytest.approx(0.125)
    assert summary["rudder_effectiveness"] == pytest.approx(0.75)
    assert summary["damage_from_shell"]["overstressed_area_fraction"]["wing_1"] == pytest.approx(0.5)


def run_flight_in(stage_dir, flight, shell_dir):
    from flexnet_fe.flight.stage import run_flight

    stage_dir.mkdir()
    return run_flight(flight, 8000.0, stage_dir, logging.getLogger("test.flight"), shell_dir=shell_dir)


def test_damage_from_shell_needs_an_allowable_stress():
    with pytest.raises(ValueError, match="damage_allowable_stress"):
        FlightConfig(damage_from_shell=True)
