"""build_sweep_report on synthetic sweep.csv / batch.csv tables written like
``flexnet_fe.sweep.run_many`` (label, override columns, flattened summary keys, error).

References: the rows the test writes (known inputs). The HTML table rounds to 6 significant
digits: relative 5e-6.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest

from flexnet_fe.errors import FlexnetError
from flexnet_fe.report import build_sweep_report
from flexnet_fe.report.sweep import numeric_outputs, override_columns, read_table, swept_parameters

from .synthetic import parse_html

SIX_DIGITS = 5e-6


def _write(path: Path, rows: list[dict]) -> Path:
    columns = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        w.writerows(rows)
    return path


def _sweep_rows():
    rows = []
    for d in (2e-3, 3e-3, 4e-3):
        for dmg in (0.0, 0.4):
            rows.append({"label": f"{d}_{dmg}", "net.rope_diameter": str(d), "flight.damage.wing_damage": str(dmg),
                         "collide.restitution": "0.5",
                         "deploy.max_area_m2": 25.0 * d / 1e-3 + dmg, "deploy.steps": 1000,
                         "flight.hit": dmg == 0.0, "deploy.snapshots": "net.pvd",
                         "shell.wing_1.peak_von_mises_pa": 1e8 * d / 1e-3,
                         "shell.rudder_2.peak_von_mises_pa": 3e8 - 1e8 * d / 1e-3,
                         "flight.wing_damage": dmg,
                         # a summary key with the name of a case field (the flight stage's own sweep):
                         # not an override, not a parameter
                         "flight.sweep.parameter": "damage", "error": ""})
    rows[-1] = {"label": rows[-1]["label"], "net.rope_diameter": "0.004", "flight.damage.wing_damage": "0.4",
                "collide.restitution": "0.5", "error": "NumericalError: shell dt > dt_crit"}
    return rows


def test_parameters_and_outputs_inferred(tmp_path):
    columns, rows = read_table(_write(tmp_path / "sweep.csv", _sweep_rows()))
    # overrides = the leading case-schema columns after label; swept = those with 2+ values
    assert override_columns(columns) == ["net.rope_diameter", "flight.damage.wing_damage", "collide.restitution"]
    params = swept_parameters(columns, rows)
    assert params == ["net.rope_diameter", "flight.damage.wing_damage"]
    outs = {c.name: c for c in numeric_outputs(columns, rows, skip={"label", "error", *params})}
    assert outs["flight.hit"].boolean and outs["flight.hit"].values[:2] == (1.0, 0.0)
    assert outs["deploy.max_area_m2"].values[-1] is None       # the failed row is not a point


def test_sweep_report_plots_only_headlines(tmp_path):
    table = _write(tmp_path / "sweep.csv", _sweep_rows())
    (tmp_path / "0.002_0.0").mkdir()
    (tmp_path / "0.002_0.0" / "report.html").write_text("<html></html>")
    html_path = build_sweep_report(table)
    assert html_path == tmp_path / "sweep_report.html"
    html = html_path.read_text()
    tree = parse_html(html)
    body = tree.tables["sweep-table"]
    assert len(body) == 1 + 6                                    # header + one row per run
    row0 = dict(zip(body[0], body[1]))
    assert float(row0["deploy.max_area_m2"]) == pytest.approx(50.0, rel=SIX_DIGITS)
    assert float(row0["shell.wing_1.peak_von_mises_pa"]) == pytest.approx(2e8, rel=SIX_DIGITS)
    assert '<a href="0.002_0.0/report.html">' in html           # link to the run's own report
    assert "NumericalError: shell dt &gt; dt_crit" in html       # failed run listed with its error
    # only headline columns are plotted (not deploy.steps, not the fins one by one)
    plotted = [r[0] for r in tree.tables["plotted"][1:]]
    assert plotted == ["deploy.max_area_m2", "shell.max_fin_peak_von_mises_pa", "flight.wing_damage", "flight.hit"]
    # one figure per swept parameter, one panel per headline; 5 successful runs per panel
    pngs = sorted(p.name for p in (tmp_path / "sweep_report_files").glob("*.png"))
    assert pngs == ["headlines__vs__flight.damage.wing_damage.png", "headlines__vs__net.rope_diameter.png"]
    assert all((tmp_path / src).is_file() for src in tree.images) and len(tree.images) == 2
    caps = re.findall(r"<figcaption>[^<]*points per panel: ([^<]*)</figcaption>", html)
    assert caps == ["deploy.max_area_m2 5, shell.max_fin_peak_von_mises_pa 5, flight.wing_damage 5, flight.hit 5"] * 2
    # the computed headline: the largest fin peak of each row, shown in MPa in the headline table
    comp = {r[0]: dict(zip(tree.tables["comparison"][0], r)) for r in tree.tables["comparison"][1:]}
    assert float(comp["0.002_0.0"]["largest fin peak von Mises [MPa]"]) == pytest.approx(200.0, rel=1e-3)
    assert float(comp["0.003_0.0"]["largest fin peak von Mises [MPa]"]) == pytest.approx(300.0, rel=1e-3)
    # no noise: the one-valued override is listed as name = value; summary keys are not overrides
    assert "<code>collide.restitution = 0.5</code>" in html
    assert "flight.sweep.parameter =" not in html and "Fixed overrides" not in html


def test_batch_report_is_a_comparison_table(tmp_path):
    rows = [{"label": "traction_deploy", "deploy.max_area_m2": 101.0, "error": ""},
            {"label": "rotary_deploy", "deploy.max_area_m2": 110.0, "error": ""},
            {"label": "flight_baseline", "flight.miss_distance_m": 1.5, "flight.hit": True, "error": ""},
            {"label": "broken", "error": "CaseError: x"}]
    html = build_sweep_report(_write(tmp_path / "batch.csv", rows)).read_text()
    tree = parse_html(html)
    assert "batch report" in html and tree.images == []           # no line plot between cases
    head, *body = tree.tables["comparison"]
    assert head == ["case", "status", "largest net area [m²]", "miss distance [m]", "missile hits the aircraft"]
    assert [r[:2] for r in body] == [["traction_deploy", "ok"], ["rotary_deploy", "ok"],
                                     ["flight_baseline", "ok"], ["broken", "failed"]]   # one row per case
    assert body[0][2] == "101" and body[0][3] == "—" and body[2][3:] == ["1.5", "yes"]


def test_explicit_parameter_must_be_a_column(tmp_path):
    table = _write(tmp_path / "sweep.csv", _sweep_rows())
    with pytest.raises(FlexnetError, match="no column"):
        build_sweep_report(table, parameters=["net.youngs_modulus"])
    with pytest.raises(FlexnetError, match="not a sweep/batch table"):
        build_sweep_report(_write(tmp_path / "other.csv", [{"a": 1}]))


def test_the_sweeps_own_picture_is_shown(tmp_path):
    """A driver that draws its own picture beside its table (the engagement map writes map.csv
    and map.png) gets it at the top of the sweep report; without one nothing is added."""
    table = _write(tmp_path / "map.csv", _sweep_rows())
    (tmp_path / "map.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    tree = parse_html(build_sweep_report(table).read_text())
    assert tree.images[0] == "map.png" and len(tree.images) == 3
    (tmp_path / "map.png").unlink()
    assert "map.png" not in build_sweep_report(table).read_text()
