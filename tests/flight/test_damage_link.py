"""Shell → flight link: overstressed fin area from dolfinx XDMF envelopes (as the shell stage writes them)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from flexnet_fe.flight.config import DamageLawConfig, FlightConfig
from flexnet_fe.flight.damage import damage_from_shell, neuber_strain, read_cell_field
from flexnet_fe.io import atomic_write_json
from flexnet_fe.missile.config import FinMaterial

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


def test_neuber_strain_law():
    # Neuber's rule for an elastic–perfectly-plastic material: σ ε = σ_e²/E with σ = σ_y above yield;
    # continuous at σ_y; elastic below.
    e, sy = 71.7e9, 503e6
    eps = neuber_strain(np.array([100e6, sy, 2 * sy]), e, sy)
    assert eps == pytest.approx([100e6 / e, sy / e, 4 * sy / e], rel=1e-15)


def test_damage_fractions_and_stage_use_them(tmp_path):
    from dolfinx.mesh import CellType

    run = tmp_path / "run"
    shell = run / "shell"
    _write_envelope(shell / "wing_1" / "envelope.xdmf", CellType.quadrilateral, 4, 2,
                    lambda x, y: np.where(x < 1.0, 600e6, 1e6))          # half of wing_1 over 503 MPa
    _write_envelope(shell / "rudder_2" / "envelope.xdmf", CellType.quadrilateral, 4, 2,
                    lambda x, y: np.full_like(x, 9.0e9))                  # rudder_2: ε = σ²/(Eσ_y) = 2.2
    mat = FinMaterial()
    # overstressed_area at the material's allowable (no shell summary: the fin material's yield)
    fins, link = damage_from_shell(shell, DamageLawConfig(law="overstressed_area"), mat)
    assert link["lost_area_fraction"] == {"rudder_2": pytest.approx(1.0), "wing_1": pytest.approx(0.5)}
    assert fins.wing_damage == pytest.approx(0.125) and fins.rudder_effectiveness == pytest.approx(0.75)
    assert link["allowable_pa"]["wing_1"] == mat.yield_strength
    # failure_strain: 600 MPa gives ε = 600²/(71.7e3 · 503) = 1.0 % < 11 %: wing_1 intact; rudder_2 lost
    fins, _ = damage_from_shell(shell, DamageLawConfig(law="failure_strain"), mat)
    assert fins.remaining == pytest.approx([1, 1, 1, 1, 1, 0, 1, 1])
    # the allowable comes from the shell summary when the shell stage wrote it (its one home is the
    # fin material; the shell passes it on): 700 MPa leaves wing_1 intact
    atomic_write_json(run / "summary.json", {"shell": {"wing_1": {"allowable_pa": 700e6},
                                                      "rudder_2": {"allowable_pa": 700e6}}})
    fins, link = damage_from_shell(shell, DamageLawConfig(law="overstressed_area"), mat)
    assert link["allowable_pa"]["wing_1"] == 700e6 and fins.remaining[0] == 1.0
    flight = FlightConfig(dt=5e-4, output_dt=5e-3, damage_from_shell=True,
                          damage_law=DamageLawConfig(law="overstressed_area", threshold_factor=0.5))
    summary = run_flight_in(tmp_path / "flight", flight, shell)           # 350 MPa: half of wing_1 lost
    assert summary["wing_damage"] == pytest.approx(0.125)
    assert summary["rudder_effectiveness"] == pytest.approx(0.75)
    assert summary["damage_from_shell"]["lost_area_fraction"]["wing_1"] == pytest.approx(0.5)
    assert summary["fin_remaining"]["wing_1"] == pytest.approx(0.5)


def run_flight_in(stage_dir, flight, shell_dir):
    from flexnet_fe.flight.stage import run_flight

    stage_dir.mkdir()
    return run_flight(flight, 8000.0, stage_dir, logging.getLogger("test.flight"), shell_dir=shell_dir)


def test_old_second_home_of_the_allowable_is_refused():
    with pytest.raises(ValueError, match="damage_allowable_stress is gone"):
        FlightConfig(damage_from_shell=True, damage_allowable_stress=503e6)
