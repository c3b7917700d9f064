"""build_report on synthetic run directories (tests/report/conftest.py).

References: the values the synthetic run writes into summary.json / status.json / the XDMF files
(known inputs, not outputs of the code under test). The report shows 4 significant digits, so a
displayed number may differ from the written one by at most half a unit of the 4th digit:
relative 5e-4 (3 digits for the yield ratio: 5e-3).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexnet_fe.errors import FlexnetError
from flexnet_fe.report import build_report
from flexnet_fe.report.pictures import (Picture, StressJob, plane_normal, read_cell_fields,
                                        render_stress_isolated)
from flexnet_fe.report.units import unit_of

from .synthetic import (ENVELOPE_P1_PA, ENVELOPE_VM_PA, FLIGHT_ERROR, SUMMARY, YIELD_PA, make_run,
                      parse_html, write_cell_xdmf)

DIGITS4 = 5e-4  # half a unit of the 4th significant digit, relative
DIGITS3 = 5e-3


def _rows(tree) -> dict[str, list[str]]:
    """{first cell: other cells} over every table of the report."""
    return {r[0]: r[1:] for t in tree.tables.values() for r in t if r}


def test_headline_numbers_match_summary(run_dir):
    html = build_report(run_dir).read_text()
    rows = _rows(parse_html(html))
    # value, unit against the summary.json the test wrote
    assert float(rows["deploy.max_area_m2"][0]) == pytest.approx(SUMMARY["deploy"]["max_area_m2"], rel=DIGITS4)
    assert rows["deploy.max_area_m2"][1] == "m²"
    assert float(rows["collide.peak_accel_mps2"][0]) == pytest.approx(12345.6, rel=DIGITS4)
    assert rows["collide.peak_accel_mps2"][1] == "m/s²"
    axis = [float(v) for v in rows["collide.peak_accel_axis_mps2"][0].strip("[]").split(",")]
    np.testing.assert_allclose(axis, SUMMARY["collide"]["peak_accel_axis_mps2"], rtol=DIGITS4)
    assert float(rows["shell.dt_s"][0]) == pytest.approx(1e-7, rel=DIGITS4)
    assert rows["shell.dt_s"][1] == "s"
    assert rows["deploy.steps"][0] == "120000"           # integers exactly
    assert rows["deploy.period_s"][0] == "—"              # JSON null shown as missing, not 0
    assert rows["deploy.air.on"][0] == "no"
    assert rows["collide.passed_through"][0] == "yes"
    assert float(rows["deploy.air.density_kgpm3"][0]) == pytest.approx(0.5258, rel=DIGITS4)
    assert "shell.wing_1.peak_von_mises_pa" not in rows   # fins go to the stress table


def test_fin_stress_table_and_yield_ratio(run_dir):
    tree = parse_html(build_report(run_dir).read_text())
    header, wing = tree.tables["fin-stress"][0], tree.tables["fin-stress"][1]
    assert header[1] == "peak von Mises [MPa]"
    assert wing[0] == "wing_1"
    assert float(wing[1]) == pytest.approx(ENVELOPE_VM_PA.max() / 1e6, rel=DIGITS4)
    assert float(wing[2]) == pytest.approx(1.5, rel=DIGITS4)            # 1.5e-3 s in ms
    assert wing[3] == "[-0.85, 0.1, 0.25]"
    assert float(wing[4]) == pytest.approx(ENVELOPE_P1_PA.max() / 1e6, rel=DIGITS4)
    # σ_vm / σ_y with σ_y = 503 MPa from resolved.json case.missile.material
    assert float(wing[5]) == pytest.approx(ENVELOPE_VM_PA.max() / YIELD_PA, rel=DIGITS3)


def test_failed_stage_shown_failed_with_error(run_dir):
    html = build_report(run_dir).read_text()
    tree = parse_html(html)
    status = {r[0]: r for r in tree.tables["stage-status"][1:]}
    assert status["flight"][2] == "failed"
    assert status["flight"][4] == FLIGHT_ERROR
    assert all(status[s][2] == "done" for s in ("deploy", "collide", "shell"))
    # the failed stage's leftover summary section is not presented as a result
    rows = _rows(tree)
    assert not any(k.startswith("flight.") for k in rows)
    assert "987.7" not in html and "987.654" not in html
    assert "Stage <b>flight</b> FAILED" in html
    assert "ERROR stage flight failed" in html            # tail of flight/log.txt


def test_pictures_and_plots_referenced(run_dir):
    html = build_report(run_dir).read_text()
    tree = parse_html(html)
    for src in tree.images:
        assert (run_dir / src).is_file(), src             # relative paths that resolve
    assert "deploy/deploy.png" in tree.images and "collide/collide_accel.png" in tree.images
    assert "report_files/shell_wing_1_von_mises.png" in tree.images
    assert "report_files/shell_von_mises_history.png" in tree.images
    # the envelope maximum read back equals the summary peak: no mismatch note
    assert "differs from summary.json" not in html


def test_html_escapes_case_text(run_dir):
    html = build_report(run_dir).read_text()
    assert "synthetic run &lt;for&gt; the report tests" in html
    assert "<for>" not in html


def test_envelope_read_back_cell_by_cell(run_dir):
    """Reader check: each cell value sits on the cell the writer placed it on (by midpoint)."""
    grid, fields, t = read_cell_fields(run_dir / "shell" / "wing_1" / "envelope.xdmf")
    assert t == 0.0
    centres = np.asarray(grid.cell_centers().points)
    ref = np.array([[-0.95, 0.1, 0.15], [-0.85, 0.1, 0.15], [-0.95, 0.1, 0.25], [-0.85, 0.1, 0.25]])
    for c, vm, p1 in zip(centres, fields["peak_von_mises_pa"], fields["peak_max_principal_pa"]):
        k = int(np.argmin(np.linalg.norm(ref - c, axis=1)))
        assert np.linalg.norm(ref[k] - c) < 1e-12
        assert vm == ENVELOPE_VM_PA[k] and p1 == ENVELOPE_P1_PA[k]   # float64 round trip: exact


def test_fields_xdmf_nearest_time_and_max_over_surfaces(tmp_path):
    rng = np.random.default_rng(1)
    data = {f"von_mises_{s}_pa": [(t, rng.uniform(0, 1e8, 4)) for t in (0.0, 1e-3, 2e-3)]
            for s in ("top", "mid", "bottom")}
    path = tmp_path / "fields.xdmf"
    write_cell_xdmf(path, data)
    # rendered in the child process (this test process has dolfinx loaded, see pictures.py)
    pic, missing = render_stress_isolated([StressJob(str(path), str(tmp_path / "p.png"), 1.4e-3),
                                           StressJob(str(tmp_path / "none.xdmf"), str(tmp_path / "q.png"))])
    assert isinstance(pic, Picture) and "no such file" in missing
    assert pic.time_s == 1e-3                              # nearest output time to 1.4 ms
    expected = np.max([v[1][1] for v in data.values()])   # max over surfaces and cells at 1 ms
    assert pic.max_pa == expected
    assert pic.field.startswith("max of ")
    from PIL import Image
    img = np.asarray(Image.open(pic.png).convert("L"), dtype=float)
    assert img.std() > 1.0                                 # not a blank image


def test_missing_optional_files_do_not_crash(tmp_path):
    run = make_run(tmp_path / "run", xdmf=False, missile=False)
    for p in (run / "deploy").glob("*.png"):
        p.unlink()
    (run / "shell" / "wing_1" / "history.csv").unlink()
    html = build_report(run).read_text()
    tree = parse_html(html)
    wing = tree.tables["fin-stress"][1]
    assert wing[5] == "—"                                  # no yield strength: no ratio
    assert "no ratio to yield: the resolved case has no [missile] table" in html
    assert "no envelope.xdmf or fields.xdmf for this fin" in html


def test_broken_xdmf_is_a_note(run_dir):
    (run_dir / "shell" / "wing_1" / "envelope.h5").unlink()
    html = build_report(run_dir).read_text()
    parse_html(html)
    assert "stress picture of fin &#39;wing_1&#39;" in html and "cannot read" in html


def test_status_only_and_done_without_section(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "status.json").write_text(json.dumps({"case": "c", "stages": {
        "deploy": {"state": "done"}, "collide": {"state": "running"}}}))
    html = build_report(run).read_text()
    tree = parse_html(html)
    status = {r[0]: r for r in tree.tables["stage-status"][1:]}
    assert status["deploy"][2] == "done (no summary section)"
    assert status["collide"][2] == "running"
    assert "resolved.json is missing" in html and "summary.json is missing" in html
    assert "stage &#39;deploy&#39; is done in status.json but summary.json has no" in html


def test_not_a_run_directory(tmp_path):
    with pytest.raises(FlexnetError, match="not a run directory"):
        build_report(tmp_path)
    with pytest.raises(FlexnetError, match="no such run directory"):
        build_report(tmp_path / "nope")


def test_plane_normal_of_a_tilted_plane():
    # points on the plane n·x = 0.3 with n = (1, 2, 2)/3: the fitted normal is ±n (exact up to
    # round-off of the SVD, ~1e-15)
    n = np.array([1.0, 2.0, 2.0]) / 3.0
    a = np.cross(n, [1.0, 0, 0]); a /= np.linalg.norm(a)
    b = np.cross(n, a)
    uv = np.random.default_rng(0).uniform(-1, 1, (50, 2))
    pts = 0.3 * n + uv[:, :1] * a + uv[:, 1:] * b
    assert abs(abs(plane_normal(pts) @ n) - 1.0) < 1e-12


@pytest.mark.parametrize("key, label, scale", [
    ("max_area_m2", "m²", 1.0), ("dt_s", "s", 1.0), ("peak_accel_mps2", "m/s²", 1.0),
    ("shell.wing_1.peak_von_mises_pa", "MPa", 1e-6), ("max_penetration_m", "m", 1.0),
    ("max_achieved_accel_g", "g (load factor)", 1.0), ("dofs", "", 1.0), ("dv_over_v", "", 1.0)])
def test_unit_from_suffix(key, label, scale):
    u = unit_of(key)
    assert (u.label, u.scale) == (label, scale)


def test_unrequested_pending_stage_only_in_status_table(tmp_path):
    from flexnet_fe.io import atomic_write_json

    run = tmp_path / "run"
    atomic_write_json(run / "resolved.json", {"case": {"case": {"name": "d", "stages": ["deploy"]}}})
    atomic_write_json(run / "status.json", {"case": "d", "stages": {
        "deploy": {"state": "done"}, "collide": {"state": "pending"}}})
    atomic_write_json(run / "summary.json", {"deploy": {"max_area_m2": 99.0}})
    html = build_report(run).read_text()
    status = {r[0]: r for r in parse_html(html).tables["stage-status"][1:]}
    assert status["collide"][1:3] == ["no", "pending"]
    assert 'id="stage-collide"' not in html and 'id="stage-deploy"' in html


def test_fin_table_without_shell_folder(run_dir):
    import shutil

    shutil.rmtree(run_dir / "shell")
    tree = parse_html(build_report(run_dir).read_text())
    wing = tree.tables["fin-stress"][1]
    assert wing[0] == "wing_1"
    assert float(wing[1]) == pytest.approx(ENVELOPE_VM_PA.max() / 1e6, rel=DIGITS4)


def test_failed_shell_stage_partial_pictures_labelled(run_dir):
    status = json.loads((run_dir / "status.json").read_text())
    status["stages"]["shell"] = {"state": "failed", "error": "NumericalError: energy growth"}
    (run_dir / "status.json").write_text(json.dumps(status))
    html = build_report(run_dir).read_text()
    tree = parse_html(html)
    assert "fin-stress" not in tree.tables                       # no numbers for a failed stage
    assert "fin wing_1 (no summary numbers: stage failed)" in html
    assert "Stage <b>shell</b> FAILED: NumericalError: energy growth" in html
