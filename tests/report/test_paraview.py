"""The merged missile file for ParaView (report/paraview.py), read back with pyvista.XdmfReader
(VTK's XDMF-2 reader, ParaView's "XDMF Reader").

References: the synthetic fins' known fields (tests/report/synthetic.py): von Mises top =
peak · t / t_last (the max over the surfaces), displacement u_z = DISP_RATE · t · (x + 1);
the body mesh written by hand; float64 round trips are exact.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexnet_fe.report.paraview import SURFACE_STRESS, merged_times, write_missile_files

from .synthetic import DISP_RATE, ENVELOPE_VM_PA, FIELD_TIMES_S, RUDDER_VM_PA, make_run

FINS = ("wing_1", "rudder_2")
PEAKS = {"wing_1": ENVELOPE_VM_PA, "rudder_2": RUDDER_VM_PA}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    run = make_run(tmp_path_factory.mktemp("pv") / "run")
    notes: list[str] = []
    out = write_missile_files(run / "shell", list(FINS), run / "pv", notes, peak_time_s=2e-3)
    assert notes == []
    return out


def _blocks(mb) -> dict:
    return {mb.get_block_name(k).split("[")[0]: mb[k] for k in range(mb.n_blocks)}


def test_missile_file_opens_with_all_parts_times_and_fields(files):
    import pyvista as pv

    reader = pv.XdmfReader(str(files.xdmf))
    assert reader.time_values == pytest.approx(list(FIELD_TIMES_S), abs=0.0)
    for t in FIELD_TIMES_S:
        reader.set_active_time_value(t)
        blocks = _blocks(reader.read())
        assert set(blocks) == {*FINS, "body"}
        for fin in FINS:
            b = blocks[fin]
            # displacement and every stress on the SAME block
            assert "displacement_m" in b.point_data
            assert {"von_mises_pa", "max_principal_pa", *SURFACE_STRESS} <= set(b.cell_data)
            centres = np.asarray(b.cell_centers().points)
            # cell values land on the right cells: top surface is the max, = peak · t / t_last
            expected = np.sort(PEAKS[fin] * t / FIELD_TIMES_S[-1])
            np.testing.assert_array_equal(np.sort(np.asarray(b.cell_data["von_mises_pa"])), expected)
            assert len(centres) == 4
            u = np.asarray(b.point_data["displacement_m"])
            x = np.asarray(b.points)
            np.testing.assert_allclose(u[:, 2], DISP_RATE * t * (x[:, 0] + 1.0), rtol=0, atol=1e-15)
            np.testing.assert_array_equal(u[:, :2], 0.0)
        body = blocks["body"]
        assert body.n_cells == 16 and "von_mises_pa" not in body.cell_data
        np.testing.assert_array_equal(np.asarray(body.point_data["displacement_m"]), 0.0)


def test_envelope_file_and_script(files):
    import pyvista as pv

    blocks = _blocks(pv.XdmfReader(str(files.envelope)).read())
    assert set(blocks) == {*FINS, "body"}
    for fin in FINS:
        assert float(np.max(blocks[fin].cell_data["peak_von_mises_pa"])) == PEAKS[fin].max()
    text = files.script.read_text()
    compile(text, str(files.script), "exec")                 # valid Python for pvpython
    assert '"missile.xdmf"' in text and '("CELLS", "von_mises_pa")' in text
    assert f"RescaleTransferFunction(0.0, {RUDDER_VM_PA.max()!r})" in text   # envelope max
    assert "scene.AnimationTime = 0.002" in text


def test_merged_times():
    # two fins with their own steps: times within a quarter of the smallest interval merge
    a = (0.0, 1.0e-3, 2.0e-3)
    b = (0.0, 1.01e-3, 2.02e-3, 1.5e-3)
    assert merged_times({"a": a, "b": b}) == [0.0, 1.0e-3, 1.5e-3, 2.0e-3]
