"""``[collide] resolution_check``: the headlines' moves when the rope pieces at the fins are halved."""

from __future__ import annotations

import logging

import pytest
from pydantic import ValidationError

from flexnet_fe.atmosphere import isa
from flexnet_fe.collide.config import CollideConfig
from flexnet_fe.collide.resolution import resolution_moves
from flexnet_fe.collide.scene import held_net
from flexnet_fe.collide.simulate import simulate
from flexnet_fe.collide.stage import run_collide
from flexnet_fe.missile.build import build_missile
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.net.config import TractionNet

LOG = logging.getLogger("test_resolution")


def _summary(dv, peak, imp, dur, fins):
    return {"dv_over_v": dv, "peak_accel_mps2": peak, "impulse_ns": imp, "duration_s": dur, "fin_impulse_ns": fins}


def test_moves_are_relative_to_the_finer_run_and_flag_beyond_the_tolerance():
    # Reference: the definition, (fine − coarse) / fine, by hand. Δv 0.93 → 1.00 moves +7 % (flagged
    # at 2 %), the peak 14.0 → 14.1 +0.71 % (not), rudder_2 1.0 → 1.5 +33 %; wing_9 carries 1 % of
    # the fin impulse (< SHARE_MIN) and is not checked however far it moves.
    coarse = _summary(0.93, 14.0, 10.0, 0.0104, {"wing_1": 4.0, "rudder_2": 1.0, "wing_9": 0.01})
    fine = _summary(1.00, 14.1, 10.0, 0.0104, {"wing_1": 4.0, "rudder_2": 1.5, "wing_9": 0.06})
    section, warnings = resolution_moves(coarse, fine, 0.35e-3, 0.02)
    assert section["dv_over_v_move_rel"] == pytest.approx(0.07)
    assert section["peak_accel_move_rel"] == pytest.approx(0.1 / 14.1)
    assert section["impulse_move_rel"] == 0.0 and section["duration_move_rel"] == 0.0
    assert section["fin_impulse_move_rel"] == {"wing_1": 0.0, "rudder_2": pytest.approx(1 / 3)}
    assert section["flagged"] == ["Δv/v", "rudder_2 impulse"] and len(warnings) == 2
    assert "+7.0 %" in warnings[0] and "0.7 → 0.35 mm" in warnings[0]
    # a headline the finer run does not have at all (no contact left): −100 %, finite for strict JSON
    gone, gone_w = resolution_moves(coarse, {**fine, "duration_s": 0.0}, 0.35e-3, 0.02, 0.7e-3)
    assert gone["duration_move_rel"] == -1.0 and "contact duration" in gone["flagged"]
    assert "0.7 → 0.35 mm, chords 1.4 → 0.7 mm" in gone_w[0]  # the chord of collide.adapt, halved too


def test_check_needs_a_piece_length_to_halve():
    with pytest.raises(ValidationError, match="resolution_check needs fin_piece_length"):
        CollideConfig(resolution_check=True)


def test_stage_reports_the_moves_of_the_two_runs(tmp_path):
    # Reference: a second model, the same impact run by hand at half the pieces — both the pieces
    # cut at the start and the chord they are cut to where they press (simulate is deterministic):
    # the stage's moves are exactly those of the two summaries.
    net_cfg = TractionNet(edge_length=1.0, mesh_size=0.05, rope_diameter=4.5e-3, corner_mass=1e-3,
                          transverse_modulus=1e11)
    cfg = CollideConfig(net_source="flat_taut", duration=4e-3, aim_point=(0.025, 0.025), snapshots=2,
                        fin_piece_length=4e-3, fin_piece_chord=8e-3, resolution_check=True)
    air = isa(8000.0)
    s = run_collide(net_cfg, None, MissileConfig(preset="radar"), cfg, air, None, tmp_path, LOG)
    missile = build_missile(MissileConfig(preset="radar"))
    fine = simulate(held_net(net_cfg, cfg.net_source, None), missile,
                    cfg.model_copy(update={"fin_piece_length": 2e-3, "fin_piece_chord": 4e-3, "resolution_check": False}),
                    air.gravity, LOG,
                    air_density=air.density, n_snapshots=2).summary
    expected, warnings = resolution_moves(s, fine, 2e-3, cfg.resolution_tolerance, 4e-3)
    got = dict(s["resolution_check"])
    assert got.pop("wall_s") > 0.0 and got.pop("fin_piece_chord_m") == 4e-3
    assert s["cut_segments"] > 0 and fine["cut_segments"] > 0  # the chord rule was at work in both
    assert got == expected and got["fin_impulse_move_rel"]  # fins were hit and checked
    assert all(w in s["warnings"] for w in warnings)
