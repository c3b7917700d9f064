"""build_report on synthetic run directories (tests/report/synthetic.py).

References: the values the synthetic run writes into summary.json / status.json / the XDMF files
(known inputs, not outputs of the code under test), and the margin of safety's definition
MS = allowable / σ_vm − 1. The report shows 4 significant digits, so a displayed number may
differ from the written one by at most half a unit of the 4th digit: relative 5e-4 (margins
are shown to 3 decimals: absolute 5e-4).
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from flexnet_fe.errors import FlexnetError
from flexnet_fe.report import build_report
from flexnet_fe.report.pictures import (Picture, StressJob, plane_normal, read_cell_fields,
                                        render_stress_isolated)

from .synthetic import (ENVELOPE_P1_PA, ENVELOPE_VM_PA, FLIGHT_ERROR, RUDDER_ALLOWABLE_PA, RUDDER_VM_PA,
                        SUMMARY, YIELD_PA, make_run, parse_html, write_cell_xdmf)

DIGITS4 = 5e-4  # half a unit of the 4th significant digit, relative
MS_DIGITS = 5e-4  # margins shown as %+.3f


def _rows(tree) -> dict[str, list[str]]:
    """{first cell: other cells} over every table of the report."""
    return {r[0]: r[1:] for t in tree.tables.values() for r in t if r}


def _warning_box(html: str) -> str:
    m = re.search(r'<div id="warnings">(.*?)</div>', html, re.S)
    assert m, "no warnings box"
    return m.group(1)


def test_headline_numbers_match_summary(built):
    _, _, tree = built
    rows = _rows(tree)
    # value, unit against the summary.json the test wrote
    assert float(rows["deploy.max_area_m2"][0]) == pytest.approx(SUMMARY["deploy"]["max_area_m2"], rel=DIGITS4)
    assert rows["deploy.max_area_m2"][1] == "m²"
    assert float(rows["collide.peak_accel_mps2"][0]) == pytest.approx(12345.6, rel=DIGITS4)
    assert rows["collide.peak_accel_mps2"][1] == "m/s²"
    axis = [float(v) for v in rows["collide.peak_accel_axis_mps2"][0].strip("[]").split(",")]
    np.testing.assert_allclose(axis, SUMMARY["collide"]["peak_accel_axis_mps2"], rtol=DIGITS4)
    assert float(rows["shell.dt_s"][0]) == pytest.approx(1e-7, rel=DIGITS4)
    assert rows["shell.dt_s"][1] == "s"
    assert rows["deploy.steps"] == ["120000", "count"]    # integers exactly
    assert rows["deploy.period_s"][0] == "—"              # JSON null shown as missing, not 0
    assert rows["deploy.air.on"] == ["no", ""]
    assert rows["collide.passed_through"][0] == "yes"
    assert rows["collide.fin_impulse_ns.wing_1"] == ["1.5", "N·s"]
    assert float(rows["deploy.air.density_kgpm3"][0]) == pytest.approx(0.5258, rel=DIGITS4)
    assert "shell.wing_1.peak_von_mises_pa" not in rows   # fins go to the verdict table
    assert "collide.warnings" not in rows                 # warnings go to the red box


def test_verdict_fins_match_summary_and_margins(built):
    _, html, tree = built
    head, *body = tree.tables["verdict-fins"]
    fins = {r[0]: dict(zip(head, r)) for r in body}
    assert list(fins) == ["wing_1", "rudder_2"]
    w = fins["wing_1"]
    vm = ENVELOPE_VM_PA.max()
    assert float(w["peak von Mises [MPa]"]) == pytest.approx(vm / 1e6, rel=DIGITS4)
    assert float(w["at t [ms]"]) == pytest.approx(1.5, rel=DIGITS4)
    assert w["location x, y, z (frame B) [m]"] == "[-0.85, 0.1, 0.25]"
    assert float(w["peak max principal [MPa]"]) == pytest.approx(ENVELOPE_P1_PA.max() / 1e6, rel=DIGITS4)
    assert float(w["error estimate [%]"]) == pytest.approx(3.0, rel=DIGITS4)
    # no allowable_pa for wing_1: the yield strength of resolved.json, and the report says so
    assert float(w["allowable [MPa]"]) == pytest.approx(YIELD_PA / 1e6, rel=DIGITS4)
    assert "yield strength of Al 7075-T6" in w["allowable from"]
    ms_key = next(k for k in head if k.startswith("MS"))
    assert float(w[ms_key]) == pytest.approx(YIELD_PA / vm - 1.0, abs=MS_DIGITS)   # +3.074
    assert w["verdict"] == "PASS"
    r = fins["rudder_2"]
    assert float(r["allowable [MPa]"]) == pytest.approx(RUDDER_ALLOWABLE_PA / 1e6, rel=DIGITS4)
    assert r["allowable from"] == "shell summary allowable_pa"
    assert float(r[ms_key]) == pytest.approx(RUDDER_ALLOWABLE_PA / RUDDER_VM_PA.max() - 1.0, abs=MS_DIGITS)
    assert r["verdict"] == "FAIL (within error)"          # |MS| = 0.111 ≤ error estimate 0.2
    assert 'id="overall">Fin strength: FAIL' in html
    # the missile part: Δv = dv_over_v × impact speed is not computable (no impact speed in this
    # resolved case), so |Δv|/v is shown as given; the peak acceleration says it is unfiltered
    missile = {r[0]: r[1:] for r in tree.tables["verdict-missile"][1:]}
    assert missile["|Δv| / v"][0] == "0.0123"
    assert missile["peak CG acceleration"][0] == "1.235e+04 m/s² at 1 ms"
    assert "NOT CFC-filtered" in missile["peak CG acceleration"][1]
    assert missile["net"][0] == "passed through"


def test_warnings_in_red_box_at_the_top(built):
    _, html, _ = built
    box = _warning_box(html)
    assert html.index('id="warnings"') < html.index('id="verdict"')      # before the verdict
    assert "forced &lt;warning&gt; of the synthetic collide stage" in box  # summary warnings, escaped
    assert "tunnelling" in box and "7 rope-segment crossings" in box
    assert "energy balance error 0.2 exceeds the tolerance 0.05" in box
    assert "stage FAILED: " + FLIGHT_ERROR in box
    assert "fin rudder_2: peak stress error estimate 0.2 &gt; 0.1 (unconverged peak)" in box
    assert "fin rudder_1 received 0.25 N·s of contact impulse but has no shell result" in box
    assert "shell/wing_1: energy" not in box              # its balance closes: 2 + 1 − 3 = 0 J


def test_every_image_exists_and_is_a_png(built):
    from PIL import Image

    run, html, tree = built
    expected = {"report_files/missile_von_mises.png", "report_files/collide_net_events.png",
                "report_files/shell_stress_history.png", "report_files/collide_response.png",
                "report_files/energy_collide.png", "report_files/energy_shell_wing_1.png",
                "report_files/shell_wing_1_von_mises.png", "report_files/shell_rudder_2_von_mises.png",
                "deploy/deploy.png", "collide/collide_accel.png"}
    assert expected <= set(tree.images)
    for src in tree.images:
        path = run / src                                  # relative paths that resolve
        with Image.open(path) as im:
            assert im.format == "PNG" and im.width > 0 and im.height > 0, src
            assert np.asarray(im.convert("L"), dtype=float).std() > 1.0, f"{src} is blank"
    gif = run / "report_files" / "collision.gif"
    assert 'href="report_files/collision.gif"' in html
    with Image.open(gif) as im:
        assert im.format == "GIF" and im.n_frames == 4         # one frame per collide snapshot
    assert "differs from summary.json" not in html           # envelope maxima = summary peaks


def test_html_escapes_case_text(built):
    _, html, _ = built
    assert "synthetic run &lt;for&gt; the report tests" in html
    assert "<for>" not in html and "<warning>" not in html


def test_failed_stage_shown_failed_with_error(built):
    _, html, tree = built
    status = {r[0]: r for r in tree.tables["stage-status"][1:]}
    assert status["flight"][2] == "failed"
    assert status["flight"][4] == FLIGHT_ERROR
    assert all(status[s][2] == "done" for s in ("deploy", "collide", "shell"))
    # the failed stage's leftover summary section is not presented as a result
    assert not any(k.startswith("flight.") for k in _rows(tree))
    assert "987.7" not in html and "987.654" not in html
    assert "Stage <b>flight</b> FAILED" in html
    assert "ERROR stage flight failed" in html            # tail of flight/log.txt
    flight = {r[0]: r[1:] for r in tree.tables["verdict-flight"][1:]}
    assert flight["flight outcome"][0] == "no result"


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
    html = build_report(run, pictures=False).read_text()
    tree = parse_html(html)
    wing = dict(zip(tree.tables["verdict-fins"][0], tree.tables["verdict-fins"][1]))
    assert wing["allowable [MPa]"] == "—" and wing["verdict"] == "—"   # no yield strength: no margin
    assert wing["allowable from"] == "none: the resolved case has no [missile] table"
    assert "no envelope.xdmf or fields.xdmf for this fin" in html
    assert "ParaView missile file not written" in html


def test_broken_xdmf_is_a_note(run_dir):
    (run_dir / "shell" / "wing_1" / "envelope.h5").unlink()
    import shutil

    shutil.rmtree(run_dir / "collide")                     # only the fin pictures are rendered
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
    box = _warning_box(html)
    assert "interrupted" in box and "done in status.json but summary.json has no section" in box
    assert 'id="overall">Fin strength: INCOMPLETE' in html


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
    tree = parse_html(build_report(run_dir, pictures=False).read_text())
    wing = tree.tables["verdict-fins"][1]
    assert wing[0] == "wing_1"
    assert float(wing[1]) == pytest.approx(ENVELOPE_VM_PA.max() / 1e6, rel=DIGITS4)


def test_failed_shell_stage_partial_pictures_labelled(run_dir):
    status = json.loads((run_dir / "status.json").read_text())
    status["stages"]["shell"] = {"state": "failed", "error": "NumericalError: energy growth"}
    (run_dir / "status.json").write_text(json.dumps(status))
    html = build_report(run_dir, pictures=False).read_text()
    tree = parse_html(html)
    assert "verdict-fins" not in tree.tables                     # no numbers for a failed stage
    assert "Stress pictures per fin (files of a stage that is not complete)" in html
    assert "Stage <b>shell</b> FAILED: NumericalError: energy growth" in html
    assert 'id="overall">Fin strength: INCOMPLETE' in html


def test_envelope_maximum_is_checked_against_the_peak_with_load_zones(tmp_path):
    """The envelope holds every cell, the St-Venant zones around the loads included, so its
    maximum must equal the summary's peak_von_mises_with_load_zones_pa, not the structural peak
    outside those zones (reference: shell.stage writes both; a real run's envelope maximum equals
    the former to round-off). A mismatch with the former is still reported."""
    from types import SimpleNamespace

    from flexnet_fe.report.figures import _fin_caption

    run = SimpleNamespace(run_dir=tmp_path)
    result = {"max_pa": 75.2e6, "png": str(tmp_path / "wing_1.png"), "field": "von_mises_pa"}
    res = {"peak_von_mises_pa": 26.1e6, "peak_von_mises_with_load_zones_pa": 75.2e6}
    notes: list[str] = []
    _fin_caption(run, "wing_1", res, "envelope", result, notes)
    assert notes == []
    _fin_caption(run, "wing_1", dict(res, peak_von_mises_with_load_zones_pa=80e6), "envelope", result, notes)
    assert len(notes) == 1 and "peak_von_mises_with_load_zones_pa" in notes[0]


def test_envelope_picture_scale_ends_at_the_structural_peak(tmp_path):
    """The fin's envelope picture: its colour scale ends at the summary's structural peak (the
    zones at the loads, far above it, in the above-colour), and the caption says so; without an
    envelope the field picture keeps its own scale (reference: the summary values passed in)."""
    from types import SimpleNamespace

    from flexnet_fe.report.figures import _fin_picture_job

    fin_dir = tmp_path / "shell" / "wing_1"
    fin_dir.mkdir(parents=True)
    (fin_dir / "envelope.xdmf").write_text("")
    run = SimpleNamespace(run_dir=tmp_path)
    res = {"peak_von_mises_pa": 162.9e6, "peak_location_m": [0.0, 0.1, 0.2], "peak_time_s": 3.8e-3}
    job, what = _fin_picture_job(run, "wing_1", res, tmp_path / "out")
    assert job["args"]["top_pa"] == 162.9e6 and "ends at it, 162.9 MPa" in what
    job, what = _fin_picture_job(run, "wing_1", dict(res, peak_von_mises_pa=None), tmp_path / "out")
    assert job["args"]["top_pa"] is None and "ends at it" not in what
    (fin_dir / "envelope.xdmf").unlink()
    (fin_dir / "fields.xdmf").write_text("")
    job, _ = _fin_picture_job(run, "wing_1", res, tmp_path / "out")
    assert "top_pa" not in job["args"]
