"""Case-file plumbing that does not depend on any physics section."""

from __future__ import annotations

import pytest

from flexnet_fe.config import apply_overrides, parse_override
from flexnet_fe.errors import CaseError


def test_override_values_are_toml():
    assert parse_override("net.rope_diameter=4e-3") == (["net", "rope_diameter"], 4e-3)
    assert parse_override("deploy.air=false") == (["deploy", "air"], False)
    assert parse_override("missile.preset=radar") == (["missile", "preset"], "radar")
    assert parse_override("case.stages=['deploy']") == (["case", "stages"], ["deploy"])


def test_override_applies_without_touching_input():
    data = {"net": {"kind": "traction"}}
    out = apply_overrides(data, ["net.rope_diameter=1e-3", "deploy.duration=0.5"])
    assert out == {"net": {"kind": "traction", "rope_diameter": 1e-3}, "deploy": {"duration": 0.5}}
    assert data == {"net": {"kind": "traction"}}


def test_override_needs_equals():
    with pytest.raises(CaseError, match="key=value"):
        parse_override("net.rope_diameter")


@pytest.mark.parametrize("text", ["net.mesh_size=0.1\nnet.edge_length=9", "net.mesh_size=0.1 0.2",
                                  'net.kind="rotary" x', "net..mesh_size=1", "=3"])
def test_override_must_be_one_toml_value(text):
    with pytest.raises(CaseError):
        parse_override(text)


def test_boolean_for_a_number_is_found_anywhere():
    from flexnet_fe.config import boolean_for_number

    assert boolean_for_number({"net": {"kind": "traction", "edge_length": True}}) == "net.edge_length"
    assert boolean_for_number({"collide": {"aim_point": [0.0, False]}}) == "collide.aim_point"
    assert boolean_for_number({"deploy": {"air": True}, "missile": {"wings": {"span": 1.0}}}) is None
