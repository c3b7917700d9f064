"""Units table, verdict arithmetic and the energy balance, on hand-made inputs.

References: the SI prefixes; MS = allowable / σ − 1 by hand; the glstat balance
total − external work − total(0) of terms chosen so that it is known in closed form.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexnet_fe.report.energy import classify, energy_table
from flexnet_fe.report.units import (NO_UNIT, axis_unit, format_value, plain_log_axis, unit_label, unit_of,
                                     unknown_units, with_unit)
from flexnet_fe.report.verdict import fin_verdict, margin_of_safety


@pytest.mark.parametrize("key, label, scale", [
    ("max_area_m2", "m²", 1.0), ("dt_s", "s", 1.0), ("peak_accel_mps2", "m/s²", 1.0),
    ("shell.wing_1.peak_von_mises_pa", "MPa", 1e-6), ("max_penetration_m", "m", 1.0),
    ("max_achieved_accel_g", "g (load factor)", 1.0), ("dofs", "count", 1.0), ("dv_over_v", "–", 1.0),
    ("collide.fin_impulse_ns.wing_1", "N·s", 1.0), ("impulse_ns", "N·s", 1.0),
    ("flight.autopilot.k_a_s_per_m", "s/m", 1.0), ("flight.ns_per_step", "ns", 1.0),
    ("collide.contact_stiffness", "N/m^m (m = contact exponent)", 1.0),
    ("collide.max_attitude_change_rad", "mrad", 1e3), ("omega_body_x_rps", "rad/s", 1.0),
    ("alpha_body_x_rps2", "rad/s²", 1.0), ("collide.segment_crossings_unresolved", "count", 1.0),
    ("flight.damage_from_shell.overstressed_area_fraction.wing_1", "–", 1.0),
    ("collide.delta_v_axis_mps", "m/s", 1.0), ("collide.contact_duration_s", "s", 1.0)])
def test_unit_table(key, label, scale):
    u = unit_of(key)
    assert (u.label, u.scale) == (label, scale)


def test_unknown_unit_is_flagged_not_guessed():
    assert unit_of("mystery_number") is NO_UNIT
    assert unknown_units({"a.mystery_number": 3.0, "a.flag": True, "a.name": "x", "a.dt_s": 1.0}) == ["a.mystery_number"]
    # lists: numbers need a unit, names (collide.resolution_check.flagged) and an empty list do not
    assert unknown_units({"a.mystery_list": [1.0, 2.0], "a.flagged": ["rudder_3 impulse"], "a.none": [],
                          "a.point_m": [0.0, 1.0]}) == ["a.mystery_list"]
    assert unit_of("collide.resolution_check.tolerance").label == "–"
    assert unit_label("hit", True) == "" and unit_label("dt_s", 1.0) == "s"
    assert with_unit(541.6e6, unit_of("x_pa")) == "541.6 MPa"
    assert format_value(None) == "—" and format_value(True) == "yes"


@pytest.mark.parametrize("peak, label, scale", [
    (4.5e-5, "µrad", 1e6), (3e-2, "mrad", 1e3), (2.0, "rad", 1.0), (0.0, "rad", 1.0)])
def test_axis_unit_prefix(peak, label, scale):
    u = axis_unit("attitude_change_rad", peak)
    assert (u.label, u.scale) == (label, scale)
    assert axis_unit("x_j", 2.5e4).label == "kJ" and axis_unit("x_pa", 5e8).label == "MPa"


def test_plain_log_ticks():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.set_yscale("log")
    ax.set_ylim(0.5, 40.0)
    plain_log_axis(ax.yaxis)
    fig.canvas.draw()
    labels = [t.get_text() for t in ax.get_yticklabels() if t.get_text()]
    minor = [t.get_text() for t in ax.yaxis.get_minorticklabels() if t.get_text()]
    plt.close(fig)
    assert "1" in labels and "10" in labels and not any("times" in s or "^" in s for s in labels)
    assert minor == []                                    # no '4×10⁰' minor labels


def test_margin_of_safety_and_allowable_source():
    assert margin_of_safety(503e6, 541.6e6) == pytest.approx(503 / 541.6 - 1)   # −0.0713
    assert margin_of_safety(1.0, 0.0) == math.inf
    own = fin_verdict("f", {"peak_von_mises_pa": 250e6, "allowable_pa": 300e6}, 503e6, "Al")
    assert own.allowable_pa == 300e6 and own.allowable_source == "shell summary allowable_pa"
    assert own.margin == pytest.approx(0.2) and own.passed and not own.marginal
    fallback = fin_verdict("f", {"peak_von_mises_pa": 600e6, "peak_error_estimate_rel": 0.05}, 503e6, "Al")
    assert fallback.allowable_pa == 503e6 and "yield strength of Al" in fallback.allowable_source
    assert fallback.passed is False and not fallback.marginal          # MS = −0.162, |MS| > 5 %
    none = fin_verdict("f", {"peak_von_mises_pa": 600e6}, None, "no material")
    assert none.margin is None and none.passed is None


def test_energy_classes_and_balance():
    assert [classify(c) for c in ("net_kinetic_j", "strain_energy_j", "contact_energy_j", "friction_j",
                                  "external_work_j", "energy_balance_j", "hub_j")] == \
        ["kinetic", "internal", "contact", "dissipated", "external_work", "balance", "other"]
    t = np.linspace(0.0, 1.0, 5)
    # KE 10 → 4, IE 0 → 3, dissipated 0 → 2, work 0 → 1: total − W − total(0) = −2 t·... closed form
    h = {"t_s": t, "kinetic_j": 10 - 6 * t, "elastic_j": 3 * t, "damping_j": 2 * t, "external_work_j": 1 * t}
    tab = energy_table("x", h)
    np.testing.assert_allclose(tab.total_j, 10 - t)
    np.testing.assert_allclose(tab.balance_j, -2 * t)             # (10 − t) − t − 10
    assert tab.balance_from == "report"
    np.testing.assert_allclose(tab.error_rel, -2 * t / 10.0)      # scale = max |total| = 10 J
    h["energy_balance_j"] = 0.5 * t                               # the stage's own balance wins
    tab = energy_table("x", h)
    assert tab.balance_from == "energy_balance_j"
    np.testing.assert_allclose(tab.balance_j, 0.5 * t)
    assert energy_table("x", {"t_s": t, "area_m2": t}) is None


def test_new_contract_keys_in_the_verdict(tmp_path):
    """The keys the rewritten stages add (brief: window-free collide keys, CFC peak, per-fin
    allowable, nested warnings, stage energy balance) are shown, not crashed on."""
    from flexnet_fe.io import atomic_write_json, write_history_csv
    from flexnet_fe.report import build_report

    from .synthetic import parse_html

    run = tmp_path / "run"
    atomic_write_json(run / "resolved.json", {"case": {"case": {"name": "n", "stages": ["collide", "shell"]},
                                                       "collide": {"impact_speed": 500.0}}})
    atomic_write_json(run / "status.json", {"case": "n", "stages": {"collide": {"state": "done"},
                                                                    "shell": {"state": "done"}}})
    atomic_write_json(run / "summary.json", {
        "collide": {"peak_accel_mps2": 700.0, "cfc": 1000, "delta_v_mps": 0.0381, "delta_v_axis_mps": [0.038, 0, 0],
                    "impulse_ns": 8.8, "fin_impulse_ns": {"wing_1": 3.9}, "contact_duration_s": 0.0081,
                    "passed_through": False, "energy_error_rel": 0.01,
                    "warnings": ["collide: Δv/v moves +2.5 % when the rope pieces at the fins are halved"]},
        "shell": {"wing_1": {"peak_von_mises_pa": 400e6, "peak_time_s": 3e-3, "peak_location_m": [0, 0, 0],
                             "peak_max_principal_pa": 410e6, "allowable_pa": 450e6, "peak_error_estimate_rel": 0.02,
                             "warnings": ["peak at a re-entrant corner"]}}})
    t = np.linspace(0, 1e-3, 5)
    write_history_csv(run / "collide" / "history.csv", {"t_s": t, "missile_kinetic_j": 100 - t * 1e4,
                                                        "net_kinetic_j": t * 1e4, "energy_balance_j": 1e-3 * t})
    html = build_report(run, pictures=False).read_text()
    tree = parse_html(html)
    missile = {r[0]: r[1:] for r in tree.tables["verdict-missile"][1:]}
    assert missile["Δv of the missile"][0] == "0.0381 m/s"
    assert "CFC 1000 filtered" in missile["peak CG acceleration"][1]
    assert missile["impulse on the missile"][0] == "8.8 N·s"
    assert missile["contact duration"][0] == "0.0081 s"
    assert missile["net"][0] == "captured / carried forward"
    fin = dict(zip(tree.tables["verdict-fins"][0], tree.tables["verdict-fins"][1]))
    assert fin["allowable from"] == "shell summary allowable_pa" and fin["verdict"] == "PASS"
    assert "peak at a re-entrant corner (wing_1)" in html            # nested warning in the box
    assert "collide: Δv/v moves" not in html and "Δv/v moves +2.5 %" in html  # the stage is shown once
    energy = {r[0]: r for r in tree.tables["energy-table"][1:]}
    assert energy["collide"][1] == "energy_balance_j"                 # the stage's own balance


def test_a_run_stopped_by_its_time_cap_in_contact_has_no_outcome():
    """A collide run that stopped at its duration with the rope still pressing on the missile
    (stop_reason "duration", force_at_end_n > 0) is neither a pass-through nor a capture: the
    verdict says so and flags it (radar_traction at 12 ms: the net is still on the rudders)."""
    from flexnet_fe.report.verdict import _outcome_item

    base = {"passed_through": False, "stop_reason": "duration", "end_time_s": 0.012, "force_at_end_n": 6091.4}
    item = _outcome_item(base)
    assert item.bad and "outcome not determined" in item.value and "12 ms" in item.value
    assert _outcome_item({**base, "stop_reason": "interaction_over", "force_at_end_n": 0.0}).value == \
        "captured / carried forward"
    assert not _outcome_item({**base, "passed_through": True}).bad


def test_the_fin_coupling_row_names_the_fin_whose_impulse_changed_most():
    """Under the staggered fin coupling the collide table says so and names the fin whose impulse
    the fins' motion changed most in N s with its own move — radar × rotary's rudder_4 (−3.13 % of
    1.185 N s), not rudder_2's graze (−7.4 % of 0.03 N s) — from summary values (run 2026-11-29)."""
    from flexnet_fe.report.verdict import _coupling_item

    fc = {"rigid": {"fin_impulse_ns": {"wing_1": 6.4999, "rudder_2": 0.03049, "rudder_3": 0.0, "rudder_4": 1.18544}},
          "fin_impulse_move_rel": {"wing_1": 0.00192, "rudder_2": -0.0744, "rudder_3": None, "rudder_4": -0.0313},
          "fin_impulse_largest_move_rel": 0.0042, "dv_over_v_move_rel": -0.00055}
    item = _coupling_item(fc)
    assert item.value.startswith("staggered") and "rudder_4's impulse -3.13 %" in item.value and not item.bad
    assert "0.42 %" in item.note and "Δv/v -0.055 %" in item.note
    none = _coupling_item({"rigid": {"fin_impulse_ns": {"wing_1": 0.0}}, "fin_impulse_move_rel": {"wing_1": None},
                           "fin_impulse_largest_move_rel": None, "dv_over_v_move_rel": None})  # no contact at all
    assert none.value.startswith("staggered") and "against" not in none.value


def test_flight_damage_from_the_shell_shows_every_fin_that_lost_area(tmp_path):
    """The flight's link to the shell stage (flight.damage.damage_from_shell: lost_area_fraction
    per fin) is shown fin by fin — a rudder's loss is not hidden behind a 'wing damage 0 %'."""
    from flexnet_fe.io import atomic_write_json
    from flexnet_fe.report import build_report

    from .synthetic import parse_html

    run = tmp_path / "run"
    atomic_write_json(run / "resolved.json", {"case": {"case": {"name": "n", "stages": ["flight"]}}})
    atomic_write_json(run / "status.json", {"case": "n", "stages": {"flight": {"state": "done"}}})
    atomic_write_json(run / "summary.json", {"flight": {
        "hit": True, "miss_distance_m": 0.32, "lethal_radius_m": 5.0, "wing_damage": 0.0,
        "damage_from_shell": {"law": "failure_strain", "failure_strain": 0.11, "allowable_from": "shell summary",
                              "lost_area_fraction": {"wing_1": 0.0, "rudder_2": 0.00428, "rudder_3": 0.00461}}}})
    tree = parse_html(build_report(run, pictures=False).read_text())
    flight = {r[0]: r[1:] for r in tree.tables["verdict-flight"][1:]}
    row = flight["fin area lost, used by the flight (from the shell stage)"]
    assert row[0] == "rudder_2 0.428 %, rudder_3 0.461 %"
    assert "failure strain 0.11" in row[1]


def test_a_stage_the_case_does_not_run_is_not_a_missing_result(tmp_path):
    """radar_rotary runs deploy, collide, shell: its status.json lists flight as pending. The
    verdict shows no flight outcome for it (before: a red "no result"); a requested flight stage
    that has not run still shows "no result"."""
    from flexnet_fe.io import atomic_write_json
    from flexnet_fe.report.rundir import read_run
    from flexnet_fe.report.verdict import _flight_items

    run = tmp_path / "run"
    for stages in (["deploy"], ["deploy", "flight"]):
        atomic_write_json(run / "resolved.json", {"case": {"case": {"name": "n", "stages": stages}}})
        atomic_write_json(run / "status.json", {"case": "n", "stages": {"deploy": {"state": "done"},
                                                                        "flight": {"state": "pending"}}})
        atomic_write_json(run / "summary.json", {"deploy": {}})
        items = _flight_items(read_run(run))
        assert [(i.label, i.value) for i in items] == ([] if stages == ["deploy"] else [("flight outcome", "no result")])


def test_the_verdict_names_the_load_sampling_its_peaks_depend_on(tmp_path):
    """A shell summary with load_sample_interval_s (shell.stage.load_sampling_warning) qualifies PASS
    with that interval — coarse, the peaks are under-estimated; fine, they still follow the rope —
    and without it (older runs) it does not."""
    from flexnet_fe.io import atomic_write_json
    from flexnet_fe.report.rundir import read_run
    from flexnet_fe.report.verdict import build_verdict

    run = tmp_path / "run"
    fin = {"peak_von_mises_pa": 1e8, "allowable_pa": 5e8, "peak_error_estimate_rel": 0.01}
    atomic_write_json(run / "resolved.json", {"case": {"case": {"name": "n", "stages": ["shell"]}}})
    atomic_write_json(run / "status.json", {"case": "n", "stages": {"shell": {"state": "done"}}})
    for extra, said in (({"load_sample_interval_s": 1e-5}, True), ({}, False)):
        atomic_write_json(run / "summary.json", {"shell": {"wing_1": fin, **extra}})
        v = build_verdict(read_run(run))
        assert v.overall == "PASS" and ("10 µs sampling" in v.overall_reason) is said
        assert ("under-estimates the peaks" in v.overall_reason) is said
    # sampled finely enough (shell.stage.LOAD_SAMPLING_RESOLVED_S): named, with what it still misses
    atomic_write_json(run / "summary.json", {"shell": {"wing_1": fin, "load_sample_interval_s": 3.125e-7,
                                                       "load_sampling_resolved": True}})
    v = build_verdict(read_run(run))
    assert "0.312 µs sampling" in v.overall_reason and "not converged in the rope" in v.overall_reason
    assert "under-estimates" not in v.overall_reason


def test_a_pass_within_the_error_estimate_is_undecided(tmp_path):
    """Reference: the margin of safety's definition. σ = 450 MPa against 503 MPa is MS = +0.118; with
    a 20 % error estimate σ (1 + 0.2) = 540 MPa exceeds the allowable, so the pass is not decided —
    the banner says UNDECIDED and names the fin; with a 5 % estimate (472 MPa) it is a PASS; a fin
    failing within its estimate (560 MPa, MS = −0.10, 20 %) keeps the banner at FAIL."""
    from flexnet_fe.io import atomic_write_json
    from flexnet_fe.report.rundir import read_run
    from flexnet_fe.report.verdict import build_verdict

    run = tmp_path / "run"
    atomic_write_json(run / "resolved.json", {"case": {"case": {"name": "n", "stages": ["shell"]}}})
    atomic_write_json(run / "status.json", {"case": "n", "stages": {"shell": {"state": "done"}}})
    safe = {"peak_von_mises_pa": 1e8, "allowable_pa": 5.03e8, "peak_error_estimate_rel": 0.2}
    for close, err, fail, overall in ((4.5e8, 0.2, None, "UNDECIDED"), (4.5e8, 0.05, None, "PASS"),
                                      (4.5e8, 0.2, 5.6e8, "FAIL")):
        fins = {"wing_1": safe, "rudder_2": {"peak_von_mises_pa": close, "allowable_pa": 5.03e8,
                                             "peak_error_estimate_rel": err}}
        if fail:
            fins["rudder_3"] = {"peak_von_mises_pa": fail, "allowable_pa": 5.03e8, "peak_error_estimate_rel": 0.2}
        atomic_write_json(run / "summary.json", {"shell": fins})
        v = build_verdict(read_run(run))
        assert v.overall == overall, (close, err, fail)
        assert ("rudder_2" in v.overall_reason) is (overall == "UNDECIDED")


def test_a_fin_whose_loads_alternate_decides_nothing(tmp_path):
    """Reference: collide.metrics.load_alternation_runs' meaning — a load alternating from one sample
    to the next for more than the limit is an explicit step past its stability limit, so the fin's
    peak is step noise (docs/validation.md, "Contact damping at the explicit limit"). Such a fin can
    neither pass nor fail the verdict: with every other fin safe the banner is UNDECIDED and names it
    (not PASS, even though its own MS ≥ 0; not FAIL, even when its noise peak exceeds the allowable);
    another fin's real failure keeps FAIL. At or below the limit, or without the limit in the summary
    (older runs), nothing changes."""
    from flexnet_fe.io import atomic_write_json
    from flexnet_fe.report.rundir import read_run
    from flexnet_fe.report.verdict import build_verdict

    run = tmp_path / "run"
    atomic_write_json(run / "resolved.json", {"case": {"case": {"name": "n", "stages": ["collide", "shell"]}}})
    atomic_write_json(run / "status.json", {"case": "n", "stages": {"collide": {"state": "done"},
                                                                   "shell": {"state": "done"}}})
    safe = {"peak_von_mises_pa": 1e8, "allowable_pa": 5e8, "peak_error_estimate_rel": 0.01}
    over = {"peak_von_mises_pa": 9e8, "allowable_pa": 5e8, "peak_error_estimate_rel": 0.01}
    cases = (  # (rudder_1's alternation run, limit key present, rudder_1, wing_1) -> banner
        (2091, True, safe, safe, "UNDECIDED"), (2091, True, over, safe, "UNDECIDED"),
        (2091, True, safe, over, "FAIL"), (8, True, safe, safe, "PASS"), (8, True, over, safe, "FAIL"),
        (2091, False, safe, safe, "PASS"))
    for runs, keyed, rudder, wing, banner in cases:
        collide = {"fin_load_alternation_samples": {"rudder_1": runs, "wing_1": 1}}
        if keyed:
            collide["fin_load_alternation_limit_samples"] = 8
        atomic_write_json(run / "summary.json", {"collide": collide,
                                                 "shell": {"rudder_1": rudder, "wing_1": wing}})
        v = build_verdict(read_run(run))
        assert v.overall == banner, (runs, keyed, banner)
        flagged = runs > 8 and keyed
        assert [f.name for f in v.fins if f.loads_alternate] == (["rudder_1"] if flagged else [])
        assert ("rudder_1" in v.overall_reason) is (flagged or (banner == "FAIL" and rudder is over))


def test_the_verdict_says_how_each_error_estimate_was_made():
    # Reference: the shell summary's keys (shell.stage.finish_fin, check_peaks): the ZZ recovery's
    # estimate, or shell.peak_check's mesh halving with the finer peak; older summaries have neither.
    from flexnet_fe.report.verdict import fin_verdict

    zz = fin_verdict("w", {"peak_von_mises_pa": 1e8, "peak_error_estimate_rel": 0.08,
                           "peak_error_estimate_kind": "zz"}, 5e8, "y")
    assert (zz.error_kind, zz.check_pa) == ("zz", None)
    mh = fin_verdict("w", {"peak_von_mises_pa": 1e8, "peak_error_estimate_rel": 0.04,
                           "peak_error_estimate_kind": "mesh_halving",
                           "peak_check": {"peak_von_mises_pa": 1.02e8}}, 5e8, "y")
    assert (mh.error_kind, mh.check_pa, mh.error_rel) == ("mesh_halving", 1.02e8, 0.04)
    old = fin_verdict("w", {"peak_von_mises_pa": 1e8, "peak_error_estimate_rel": 0.08}, 5e8, "y")
    assert (old.error_kind, old.check_pa) == (None, None)


def test_a_fin_is_held_to_its_strike_envelope():
    # Reference: MS = allowable / σ − 1 with σ the strike envelope where the shell summary has one
    # (shell.stage.check_strikes): a fin whose own strike passes and whose envelope exceeds the
    # allowable fails; the run's own peak is kept for the report; the flight outcome's margins
    # (flight.outcome.fin_margins) take the same stress.
    from flexnet_fe.flight.outcome import fin_margins
    from flexnet_fe.report.verdict import fin_verdict

    res = {"peak_von_mises_pa": 4.0e8, "strike_envelope_von_mises_pa": 5.5e8, "allowable_pa": 5.0e8}
    v = fin_verdict("rudder_2", res, None, "y")
    assert (v.von_mises_pa, v.run_pa) == (5.5e8, 4.0e8)
    assert v.margin == pytest.approx(5.0 / 5.5 - 1.0) and v.passed is False
    plain = fin_verdict("rudder_2", {"peak_von_mises_pa": 4.0e8, "allowable_pa": 5.0e8}, None, "y")
    assert plain.run_pa is None and plain.passed and plain.margin == pytest.approx(0.25)
    assert fin_margins({"shell": {"rudder_2": res}}) == {"rudder_2": pytest.approx(5.0 / 5.5 - 1.0)}
