"""Sweep plumbing: grid expansion and summary flattening."""

from __future__ import annotations

import pytest

from flexnet_fe.errors import CaseError
from flexnet_fe.sweep import flatten, parse_axis, sweep_points


def test_grid_is_the_cartesian_product():
    axes = [parse_axis("net.rope_diameter=3e-3,4e-3"), parse_axis("deploy.air=true,false")]
    pts = sweep_points(axes)
    assert len(pts) == 4
    assert pts[0] == ["net.rope_diameter=3e-3", "deploy.air=true"]
    assert pts[-1] == ["net.rope_diameter=4e-3", "deploy.air=false"]


def test_axis_needs_values():
    with pytest.raises(CaseError):
        parse_axis("net.rope_diameter=")
    with pytest.raises(CaseError):
        parse_axis("net.rope_diameter")


def test_flatten_keeps_scalars_only():
    assert flatten({"shell": {"wing_1": {"peak_von_mises_pa": 1.0, "peak_location_m": [0, 0, 0]},
                              "dt_s": 1e-7}}) == {"shell.wing_1.peak_von_mises_pa": 1.0, "shell.dt_s": 1e-7}
