"""The merged missile file for ParaView (report/paraview.py), read back with pyvista.XdmfReader
(VTK's XDMF-2 reader, ParaView's "XDMF Reader").

References: the synthetic fins' known fields (tests/report/synthetic.py): von Mises top =
peak · t / t_last (the max over the surfaces), displacement u_z = DISP_RATE · t · (x + 1);
the body mesh written by hand; float64 round trips are exact.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexnet_fe.report.paraview import SURFACE_STRESS, merge_outputs, write_missile_files

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


def test_merge_outputs():
    # two fins with their own steps (b drifts by 1 % per output) and a peak-time frame of b at
    # 1.45 ms: times within half the smallest median interval (0.5 ms) share a frame, but a fin's
    # own frames are never merged (b's 1.45 ms frame and its 2.02 ms frame stay apart)
    a = (0.0, 1.0e-3, 2.0e-3)
    b = (0.0, 1.01e-3, 1.45e-3, 2.02e-3)
    groups = merge_outputs({"a": a, "b": b})
    assert [t for t, _ in groups] == [0.0, 1.0e-3, 1.45e-3, 2.0e-3]
    assert [g for _, g in groups] == [{"a": 0, "b": 0}, {"a": 1, "b": 1}, {"b": 2, "a": 1}, {"a": 2, "b": 3}]


PV_CHECK = r'''
import json, sys
from paraview.simple import XDMFReader, servermanager
r = XDMFReader(FileNames=[sys.argv[1]])
r.UpdatePipelineInformation()
times = list(r.TimestepValues)
r.UpdatePipeline(times[-1])
d = servermanager.Fetch(r)
blocks = {}
for k in range(d.GetNumberOfBlocks()):
    b = d.GetBlock(k)
    cd, pd = b.GetCellData(), b.GetPointData()
    blocks[d.GetMetaData(k).Get(d.NAME()).split("[")[0]] = {
        "cells": b.GetNumberOfCells(),
        "cell": [cd.GetArrayName(i) for i in range(cd.GetNumberOfArrays())],
        "point": [pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())],
        "vm_max": cd.GetArray("von_mises_pa").GetRange()[1] if cd.GetArray("von_mises_pa") else None}
print("RESULT" + json.dumps({"times": times, "blocks": blocks}))
'''


def _pvpython():
    import os
    import shutil

    return os.environ.get("FLEXNET_PVPYTHON") or shutil.which("pvpython")


@pytest.mark.skipif(not _pvpython(), reason="no ParaView pvpython (postprocess/paraview_sandbox.sh makes one; "
                                            "set FLEXNET_PVPYTHON)")
def test_paraview_reads_the_missile_file(files, tmp_path):
    """ParaView's own XDMF reader (pvpython) sees the same blocks, times and fields, and the
    pvpython script renders a picture."""
    import json
    import subprocess

    from PIL import Image

    check = tmp_path / "check.py"
    check.write_text(PV_CHECK)
    p = subprocess.run([_pvpython(), str(check), str(files.xdmf)], capture_output=True, text=True, timeout=180)
    line = next((ln for ln in p.stdout.splitlines() if ln.startswith("RESULT")), None)
    assert line, p.stdout[-2000:] + p.stderr[-2000:]
    got = json.loads(line[len("RESULT"):])
    assert got["times"] == pytest.approx(list(FIELD_TIMES_S), abs=0.0)
    assert set(got["blocks"]) == {*FINS, "body"}
    for fin in FINS:
        b = got["blocks"][fin]
        assert "displacement_m" in b["point"] and {"von_mises_pa", *SURFACE_STRESS} <= set(b["cell"])
        assert b["vm_max"] == PEAKS[fin].max()                 # at the last time: peak · 1
    png = tmp_path / "pv.png"
    p = subprocess.run([_pvpython(), str(files.script), str(png)], capture_output=True, text=True, timeout=180)
    assert png.is_file(), p.stderr[-2000:]
    with Image.open(png) as im:
        assert np.asarray(im.convert("L"), dtype=float).std() > 1.0
