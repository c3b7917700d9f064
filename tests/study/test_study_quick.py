"""`flexnet study all --quick` (issue 15): it runs, writes its CSVs, PNGs and page, and every
quick-study default lies within its stated tolerance of the quick reference of the same run.

The wall time is measured and printed (pytest -s), not asserted: timings on the shared machine
vary 2–4× with the load (brief: no absolute timing in a test). Measured 2026-11-23 (issue 15,
after the merge): 55 s CPU, 151 s wall at load average ≈ 5–6 on 2 cores (collide 22 s CPU,
stability 11 s, flight 6 s, shell 4 s, deploy 2 s, throughput 1 s).
"""

from __future__ import annotations

import csv
import json
import time

import pytest

from flexnet_fe.cli import main

TOLERANCE = {
    # The bar (2 % of converged) for the stages whose reference differs from the default
    # only in resolution knobs (dt, crop, area pixel) on the reduced scenes. The quick collision
    # does not split its ropes (rope_split 1, not varied): on its 20 cm flat net the split is far
    # from converged (Δv/v 1.36e-4 / 6.8e-5 / 4.8e-5 at k = 2 / 4 / 8), so the rope resolution is
    # measured by the full study only (reference = 2 × the shipped case's rope_split).
    "deploy": 0.02,
    "collide": 0.02,
    "flight": 0.02,
}
"""Relative tolerance of each headline of the default against the quick reference.

shell: the quick scene's peak is at the clamped root corner of the fin, where the stress
gradient is steep: at the shipped 20 mm mesh the peak is 8 % below the 10 mm reference — the
default does NOT meet 2 % (stated on the page). Its tolerance is the solver's own a-posteriori
estimate of the peak's error (``peak_error_estimate_rel`` of the same run, the number the stage
reports to users): the test checks that the reported error bar covers the true error."""

ACCURACY = ("deploy", "collide", "shell", "flight")
GUARDED_MAPS = ("net", "collide", "shell", "contact")
"""Maps where a solver guard exists: none of their points may report a wrong number unflagged."""


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    t0 = time.perf_counter()
    code = main(["study", "all", "--quick", "--out", str(out)])
    print(f"\nflexnet study all --quick: {time.perf_counter() - t0:.1f} s wall")
    assert code == 0
    return out


def test_writes_csv_png_and_page(study):
    for name in ACCURACY + ("stability", "simplify", "throughput"):
        path = study / f"{name}.csv"
        assert path.is_file() and path.stat().st_size > 0, path
        with open(path) as fh:
            assert len(list(csv.DictReader(fh))) >= 1, path
    for png in [f"{n}_accuracy.png" for n in ACCURACY] + ["stability_dt.png", "stability_contact.png",
                                                          "stability_damping.png"]:
        assert (study / png).stat().st_size > 10_000, png
    page = (study / "README.md").read_text()
    for n in ACCURACY:
        assert f"![{n}: accuracy against cost]({n}_accuracy.png)" in page
    assert "load average" in page and "cores" in page


def _default_and_reference(study, name):
    rows = json.loads((study / f"{name}.json").read_text())["rows"]
    d = next(r for r in rows if r["is_default"])
    ref = next(r for r in rows if r["is_reference"])
    assert d["status"] == "ok" and ref["status"] == "ok"
    return d, ref, [k for k in d if k.startswith("err_")]


@pytest.mark.parametrize("name", sorted(TOLERANCE))
def test_default_within_tolerance_of_reference(study, name):
    d, ref, errs = _default_and_reference(study, name)
    assert errs
    for k in errs:
        assert d[k] <= TOLERANCE[name], f"{name}: default {k} = {d[k]:.3g} > {TOLERANCE[name]}"


def test_shell_default_within_its_own_error_estimate(study):
    d, ref, errs = _default_and_reference(study, "shell")
    assert d["err_peak_von_mises_pa"] <= d["peak_error_estimate_rel"], (
        f"shell: true error {d['err_peak_von_mises_pa']:.3g} exceeds the solver's estimate "
        f"{d['peak_error_estimate_rel']:.3g}")


def test_guards_let_no_wrong_number_escape(study):
    rows = json.loads((study / "stability.json").read_text())["rows"]
    for m in GUARDED_MAPS:
        mine = [r for r in rows if r["map"] == m]
        assert mine, m
        assert any(r["status"] == "stopped" for r in mine), f"{m}: the map never reaches the guard"
        escaped = [r for r in mine if r["escaped"]]
        assert not escaped, f"{m}: wrong numbers escaped: {escaped}"
