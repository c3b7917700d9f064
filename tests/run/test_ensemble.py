"""Ensembles (``flexnet_fe.ensemble``): the members' aim points against the R2 sequence's closed
form, their overrides as valid cases, the statistics against Python's ``statistics`` module, the
fin stress each member is held to, the files, and one-line refusals. (Running and reusing the
members is the sweep's, tested in tests/test_sweep.py and tests/run/test_sweep_resume.py; a
measured ensemble is in docs/validation.md, "Ensembles".)"""

from __future__ import annotations

import csv
import json
import math
import os
import statistics as pystats
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from flexnet_fe import ensemble as E
from flexnet_fe.config import load_case
from flexnet_fe.runs import ENSEMBLE_STATS, ENSEMBLE_TABLE
from flexnet_fe.sweep import write_table

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "radar_traction"


def test_member_offsets_are_the_r2_sequence_over_one_cell():
    cell = 0.05
    off = E.cell_offsets(64, cell)
    # closed form, Roberts' R2: g³ = g + 1 → g = 1.3247179572…; 1/g = 0.7548776662, 1/g² = 0.5698402910;
    # member 1: frac(0.5 + 0.7548776662) − 0.5 = −0.2451223338, frac(0.5 + 0.5698402910) − 0.5 = −0.4301597090
    assert E.PLASTIC ** 3 == pytest.approx(E.PLASTIC + 1.0, rel=1e-15)
    assert np.array_equal(off[0], [0.0, 0.0])  # member 0: the case as given
    assert off[1] == pytest.approx([-0.2451223338 * cell, -0.4301597090 * cell], abs=1e-11)
    assert np.all(off >= -cell / 2) and np.all(off < cell / 2)
    # an even cover for any n (low discrepancy): each quarter of the cell holds n/4 ± 2 of the first n
    for n in (8, 16, 64):
        q = np.histogram2d(off[:n, 0], off[:n, 1], bins=2, range=[[-cell / 2, cell / 2]] * 2)[0]
        assert np.all(np.abs(q - n / 4) <= 2), (n, q)


def test_members_are_the_case_with_its_aim_point_moved():
    case, _ = load_case(CASE, [])
    aim, cell = E.case_aim_and_cell(case, "case.toml", None)
    assert aim == tuple(case.collide.aim_point) and cell == case.net.mesh_size
    vs = E.members(CASE, ["shell.peak_check=false"], aim, cell, 5)
    assert [v.label for v in vs] == [f"member_{k:02d}" for k in range(5)]
    off = E.cell_offsets(5, cell)
    for v, (dx, dy) in zip(vs, off):
        c, _ = load_case(v.case_path, list(v.overrides))
        assert c.collide.aim_point == pytest.approx((aim[0] + dx, aim[1] + dy), abs=1e-15)
        assert c.shell.peak_check is False
        assert dict(v.params)[E.AIM_X] == repr(c.collide.aim_point[0])


def test_statistics_against_the_statistics_module():
    vals = [310e6, 362e6, 288e6, 401e6, 335e6]
    s = E.statistics(vals, tolerance=0.02)
    mean, std = pystats.fmean(vals), pystats.stdev(vals)  # independent: stdlib, sample std (n − 1)
    assert s["n"] == 5 and s["mean"] == pytest.approx(mean, rel=1e-14) and s["std"] == pytest.approx(std, rel=1e-14)
    assert s["sem"] == pytest.approx(std / math.sqrt(5), rel=1e-14)
    assert s["sem_rel"] == pytest.approx(std / math.sqrt(5) / mean, rel=1e-14)
    assert (s["min"], s["max"]) == (288e6, 401e6)
    # members for 2 %: n with std/√n = 0.02 mean → n = (std / (0.02 mean))², rounded up
    need = math.ceil((std / (0.02 * mean)) ** 2)
    assert s["members_for_tolerance"] == need and need > 5 and s["converged"] is False
    assert E.statistics(vals, tolerance=0.5)["converged"] is True
    one = E.statistics([3.0], 0.02)
    assert one["mean"] == 3.0 and one["std"] is None and one["converged"] is False
    assert E.statistics([], 0.02)["n"] == 0
    zero = E.statistics([-1.0, 1.0], 0.02)  # a zero mean has no relative error
    assert zero["sem_rel"] is None and zero["converged"] is False and "± 1" in E.describe(
        {"tolerance": 0.02, "headlines": {"x": zero}, "fins": {}})


def test_shares_have_the_wilson_interval():
    # closed forms (Wilson 1927, z = 1.959964): k = 0 of n → [0, z²/(n + z²)]; k = n → [n/(n + z²), 1];
    # k = 5 of 10 → 0.5 ± z·√(0.025 + z²/400)/(1 + z²/10) = [0.23659, 0.76341]
    z2 = E.Z95 ** 2
    assert E.proportion(0, 10)["wilson95"] == pytest.approx([0.0, z2 / (10 + z2)], abs=1e-15)
    assert E.proportion(10, 10)["wilson95"] == pytest.approx([10 / (10 + z2), 1.0], abs=1e-15)
    assert E.proportion(5, 10)["wilson95"] == pytest.approx([0.23659, 0.76341], abs=1e-5)
    assert E.proportion(3, 12)["share"] == 0.25 and E.proportion(0, 0)["share"] is None


def _row(label, peaks, envelope=None, error=""):
    r = {"label": label, "collide.dv_over_v": 1e-4, "error": error}
    for fin, p in peaks.items():
        r[f"shell.{fin}.peak_von_mises_pa"] = p
        if envelope and fin in envelope:
            r[f"shell.{fin}.strike_envelope_von_mises_pa"] = envelope[fin]
    return r


def test_summary_holds_each_fin_to_its_envelope_and_leaves_failed_members_out():
    rows = [_row("member_00", {"wing_1": 80e6, "rudder_2": 186e6}, {"rudder_2": 363e6}),
            _row("member_01", {"wing_1": 90e6, "rudder_2": 300e6}),
            _row("member_02", {"wing_1": 70e6, "rudder_2": 250e6}, {"wing_1": 75e6}),
            {"label": "member_03", "error": "collide: blow-up"}]
    s = E.summarise(rows, 0.02)
    assert s["members"] == 4 and s["failed"] == ["member_03"]
    assert list(s["fins"]) == ["wing_1", "rudder_2"]
    assert s["fins"]["rudder_2"]["peak"]["mean"] == pytest.approx((186e6 + 300e6 + 250e6) / 3)
    assert s["fins"]["rudder_2"]["governing"]["mean"] == pytest.approx((363e6 + 300e6 + 250e6) / 3)
    assert s["fins"]["wing_1"]["governing"]["max"] == 90e6 and s["fins"]["wing_1"]["governing"]["min"] == 75e6
    # the case's largest fin stress per member: 363, 300, 250 MPa
    assert s["largest"]["mean"] == pytest.approx((363e6 + 300e6 + 250e6) / 3)
    assert s["headlines"]["collide.dv_over_v"]["n"] == 3


def test_shares_above_the_allowable_and_of_hits_read_the_csv_text_too():
    rows = [_row(f"member_{k:02d}", {"rudder_2": p, "wing_1": 80e6}, {"rudder_2": e} if e else None)
            for k, (p, e) in enumerate([(300e6, 520e6), (450e6, None), (350e6, None), (600e6, 610e6)])]
    for r, hit in zip(rows, (True, False, True, True)):
        r.update({"shell.rudder_2.allowable_pa": 500e6, "shell.wing_1.allowable_pa": 500e6, "flight.hit": hit})
    text = [{k: ("" if v is None else str(v)) for k, v in r.items()} for r in rows]  # as read back from the CSV
    for given in (rows, text):
        s = E.summarise(given, 0.02)
        # rudder_2 held to 520, 450, 350, 610 MPa against 500: members 0 and 3 above; wing_1 never
        assert (s["over_allowable"]["rudder_2"]["k"], s["over_allowable"]["rudder_2"]["n"]) == (2, 4)
        assert s["over_allowable"]["wing_1"]["k"] == 0 and s["over_allowable"]["any"]["k"] == 2
        assert (s["outcomes"]["flight.hit"]["k"], s["outcomes"]["flight.hit"]["n"]) == (3, 4)
        assert s["largest"]["max"] == 610e6
    assert "rudder_2 above its allowable: 2/4 members" in E.describe(E.summarise(rows, 0.02))


def test_run_writes_table_statistics_and_picture(tmp_path, monkeypatch):
    rows = [_row(f"member_{k:02d}", {"wing_2": 80e6 + 5e6 * k, "rudder_3": 340e6 - 9e6 * k}) for k in range(6)]
    for k, r in enumerate(rows):
        r.update({"shell.rudder_3.allowable_pa": 330e6, "flight.hit": k != 2})
    monkeypatch.setattr(E, "run_many", lambda variants, out, table, **kw: (write_table(table, rows), rows)[1])
    stats = E.run_ensemble([], tmp_path, 0.02)
    back = json.loads((tmp_path / ENSEMBLE_STATS).read_text())
    assert back == json.loads(json.dumps(stats))
    with open(tmp_path / ENSEMBLE_TABLE) as f:
        assert [r["label"] for r in csv.DictReader(f)] == [r["label"] for r in rows]
    assert (tmp_path / ENSEMBLE_TABLE).with_suffix(".png").stat().st_size > 10_000
    assert "rudder_3 (held to): 317.5 ± " in E.describe(stats)
    # `flexnet report FOLDER` finds the member table and shows the ensemble's own picture
    from flexnet_fe.cli import main

    assert main(["report", str(tmp_path)]) == 0
    html = (tmp_path / "ensemble_report.html").read_text()
    assert "ensemble.png" in html and "member_05" in html
    # its statistics table: rudder_3 held to 340 − 9k MPa, k = 0…5 → mean 317.5 MPa
    assert "ensemble report: ensemble.csv" in html and "Ensemble statistics" in html
    assert "shell.rudder_3.held_to_pa [MPa]" in html and ">317.5<" in html
    # rudder_3 above 330 MPa in members 0 and 1 (340, 331); the missile hits in 5 of 6
    assert "<td>rudder_3 above its allowable</td><td class=\"num\">2 of 6</td>" in html
    assert "<td>flight.hit</td><td class=\"num\">5 of 6</td>" in html


def test_refusals_name_the_field(tmp_path):
    def run_cli(*args):
        env = dict(os.environ, FLEXNET_NO_PROGRESS="1")
        return subprocess.run([sys.executable, "-m", "flexnet_fe.cli", *map(str, args)], capture_output=True,
                              text=True, cwd=ROOT, env=env, timeout=300)

    r = run_cli("ensemble", CASE, "--cell", "0", "--out", tmp_path / "e")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert "--cell: must be > 0 m" in r.stderr and not (tmp_path / "e").exists()
    r = run_cli("ensemble", CASE, "--tolerance", "0", "--out", tmp_path / "e")
    assert r.returncode == 2 and "--tolerance: must be > 0" in r.stderr, r.stderr
