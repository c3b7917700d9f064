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
from flexnet_fe.report.sweep import numeric_outputs, read_table, swept_parameters

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
                         "deploy.max_area_m2": 25.0 * d / 1e-3 + dmg, "deploy.steps": 1000,
                         "flight.hit": dmg == 0.0, "deploy.snapshots": "net.pvd",
                         "shell.wing_1.peak_von_mises_pa": 1e8 * d / 1e-3, "error": ""})
    rows[-1] = {"label": rows[-1]["label"], "net.rope_diameter": "0.004", "flight.damage.wing_damage": "0.4",
                "error": "NumericalError: shell dt > dt_crit"}
    return rows


def test_parameters_and_outputs_inferred(tmp_path):
    columns, rows = read_table(_write(tmp_path / "sweep.csv", _sweep_rows()))
    params = swept_parameters(columns, rows)
    # override columns are case-schema fields; summary keys are not
    assert params == ["net.rope_diameter", "flight.damage.wing_damage"]
    outs = {c.name: c for c in numeric_outputs(columns, rows, skip={"label", "error", *params})}
    assert set(outs) == {"deploy.max_area_m2", "deploy.steps", "flight.hit", "shell.wing_1.peak_von_mises_pa"}
    assert outs["flight.hit"].boolean and outs["flight.hit"].values[:2] == (1.0, 0.0)
    assert outs["deploy.max_area_m2"].values[-1] is None       # the failed row is not a point


def test_sweep_report(tmp_path):
    table = _write(tmp_path / "sweep.csv", _sweep_rows())
    (tmp_path / "0.002_0.0").mkdir()
    (tmp_path / "0.002_0.0" / "report.html").write_text("<html></html>")
    html_path = build_sweep_report(table)
    assert html_path == tmp_path / "sweep_report.html"
    html = html_path.read_text()
    tree = parse_html(html)
    body = tree.tables["sweep-table"]
    assert len(body) == 1 + 6                                    # header + one row per run
    header = body[0]
    row0 = dict(zip(header, body[1]))
    assert float(row0["deploy.max_area_m2"]) == pytest.approx(50.0, rel=SIX_DIGITS)
    assert float(row0["shell.wing_1.peak_von_mises_pa"]) == pytest.approx(2e8, rel=SIX_DIGITS)
    assert '<a href="0.002_0.0/report.html">' in html           # link to the run's own report
    assert "NumericalError: shell dt &gt; dt_crit" in html       # failed run listed with its error
    # 3 varying numeric outputs x 2 swept parameters; deploy.steps is constant (listed, not plotted)
    pngs = sorted(p.name for p in (tmp_path / "sweep_report_files").glob("*.png"))
    assert len(pngs) == 6 and not any("deploy.steps" in p for p in pngs)
    assert all((tmp_path / src).is_file() for src in tree.images) and len(tree.images) == 6
    # every successful run is a point of each plot: 5 of the 6 rows
    assert re.findall(r"\((\d+) points\)</figcaption>", html) == ["5"] * 6
    assert "deploy.steps" in {r[0] for r in tree.tables["_1"]}


def test_batch_report_plots_per_run(tmp_path):
    rows = [{"label": "traction_deploy", "deploy.max_area_m2": 101.0, "error": ""},
            {"label": "rotary_deploy", "deploy.max_area_m2": 110.0, "error": ""},
            {"label": "flight_baseline", "flight.miss_distance_m": 1.5, "error": ""}]
    html = build_sweep_report(_write(tmp_path / "batch.csv", rows)).read_text()
    parse_html(html)
    assert "none (a batch: outputs are plotted per run)" in html
    assert (tmp_path / "batch_report_files" / "deploy.max_area_m2__vs__label.png").is_file()
    assert "(2 points)" in html                                  # only the runs that have the key


def test_explicit_parameter_must_be_a_column(tmp_path):
    table = _write(tmp_path / "sweep.csv", _sweep_rows())
    with pytest.raises(FlexnetError, match="no column"):
        build_sweep_report(table, parameters=["net.youngs_modulus"])
    with pytest.raises(FlexnetError, match="not a sweep/batch table"):
        build_sweep_report(_write(tmp_path / "other.csv", [{"a": 1}]))
