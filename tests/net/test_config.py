"""The [net] and [deploy] sections refuse bad input."""

import pytest
from pydantic import TypeAdapter, ValidationError

from flexnet_fe.net.config import DeployConfig, NetConfig, RotaryNet, TractionNet, WarpInitialState

ADAPTER = TypeAdapter(NetConfig)


def test_discriminated_union_and_defaults():
    assert isinstance(ADAPTER.validate_python({"kind": "traction"}), TractionNet)
    rot = ADAPTER.validate_python({"kind": "rotary", "warp_initial_state": "rest"})
    assert isinstance(rot, RotaryNet) and rot.warp_initial_state is WarpInitialState.REST
    # the paper's §V-A values are the defaults
    t = TractionNet()
    assert (t.edge_length, t.mesh_size, t.youngs_modulus, t.density, t.corner_mass, t.corner_speed) == (
        5.0, 0.05, 1e6, 1000.0, 1.0, 100.0)
    r = RotaryNet()
    assert (r.warps, r.warp_length, r.mesh_size, r.hub_radius, r.hub_mass, r.hub_spin, r.tip_mass, r.tip_speed) == (
        8, 3.0, 0.03, 0.1, 2.8, 10.0, 0.5, 30.0)


@pytest.mark.parametrize("bad", [
    {"kind": "traction", "rope_diameter": -1e-3},
    {"kind": "traction", "colour": "red"},
    {"kind": "traction", "mesh_size": 0.0},
    {"kind": "traction", "corner_speed": float("nan")},
    {"kind": "rotary", "warp_initial_state": "spinning"},
    {"kind": "hexagonal"},
])
def test_bad_net_refused(bad):
    with pytest.raises(ValidationError):
        ADAPTER.validate_python(bad)


def test_bad_deploy_refused():
    for bad in ({"duration": -1.0}, {"safety_factor": 1.5}, {"air": "maybe"}, {"dt": 1e-4}):
        with pytest.raises(ValidationError):
            DeployConfig(**bad)
    with pytest.raises(ValidationError):  # frozen
        DeployConfig().duration = 2.0
