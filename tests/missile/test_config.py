"""The [missile] table: presets, overrides, refusals."""

import numpy as np
import pytest
from pydantic import ValidationError

from flexnet_fe.missile.config import MassModel, MissileConfig, MissilePreset, NoseShape
from flexnet_fe.missile.build import build_missile


def test_presets_differ_only_in_nose_and_name():
    # paper §V-C: "only different in shape and quality; other parameters including material and
    # aerodynamic surface parameters are the same"
    radar = MissileConfig(preset="radar").model_dump()
    infrared = MissileConfig(preset="infrared").model_dump()
    differing = {k for k in radar if radar[k] != infrared[k]}
    assert differing == {"preset", "name", "nose_shape", "nose_length"}
    assert radar["nose_shape"] is NoseShape.TANGENT_OGIVE
    assert infrared["nose_shape"] is NoseShape.HEMISPHERE


def test_sub_table_override_merges_with_preset():
    cfg = MissileConfig(preset="infrared", wings={"span": 0.5}, material={"density": 2700.0})
    assert cfg.wings.span == 0.5
    assert cfg.wings.root_chord == MissileConfig(preset="infrared").wings.root_chord
    assert cfg.material.density == 2700.0 and cfg.material.name == "Al 7075-T6"
    assert cfg.preset is MissilePreset.INFRARED


@pytest.mark.parametrize("bad", [
    {"preset": "laser"},
    {"nose_shape": "blunt"},
    {"colour": "red"},
    {"wings": {"chord": 0.3}},
    {"body_length": -1.0},
    {"body_length": float("nan")},
    {"nose_shape": "hemisphere", "nose_length": 0.2},
    {"nose_shape": "tangent_ogive", "nose_length": 0.05},
    {"wings": {"root_le_station": 0.1}},
    {"rudders": {"root_le_station": 3.5}},
    {"mass_model": "given", "mass": 200.0},
    {"mass": 200.0},
    {"mass_model": "given", "mass": 200.0, "cg": (-1.8, 0, 0),
     "inertia": ((2.0, 1.0, 0), (0, 200.0, 0), (0, 0, 200.0))},  # not symmetric
    {"mass_model": "given", "mass": 200.0, "cg": (-1.8, 0, 0),
     "inertia": ((2.0, 0, 0), (0, -200.0, 0), (0, 0, 200.0))},  # not positive definite
])
def test_refused(bad):
    with pytest.raises(ValidationError):
        MissileConfig(**{"preset": "radar", **bad})


def test_given_mass_model():
    cfg = MissileConfig(preset="radar", mass_model="given", mass=200.0, cg=(-1.8, 0.0, 0.0),
                        inertia=((2.0, 0, 0), (0, 200.0, 0), (0, 0, 200.0)))
    assert cfg.mass_model is MassModel.GIVEN
    mis = build_missile(cfg)  # taken as given, not recomputed
    assert mis.mass == 200.0 and tuple(mis.cg) == (-1.8, 0.0, 0.0)
    assert np.array_equal(mis.inertia, np.diag([2.0, 200.0, 200.0]))


def test_frozen():
    cfg = MissileConfig(preset="radar")
    with pytest.raises(ValidationError):
        cfg.body_length = 2.0


def test_preset_is_required():
    with pytest.raises(ValidationError, match="preset"):
        MissileConfig(body_length=3.0)
