"""Small scenes for the collision tests (flat taut traction nets, the radar preset missile)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from flexnet_fe.collide.config import NetSource
from flexnet_fe.collide.scene import HeldNet, held_net
from flexnet_fe.missile.config import MissileConfig
from flexnet_fe.missile.geometry import build_missile
from flexnet_fe.net.config import TractionNet


@pytest.fixture(scope="session")
def radar():
    return build_missile(MissileConfig(preset="radar"))


@pytest.fixture(scope="session")
def log():
    lg = logging.getLogger("test_collide")
    lg.setLevel(logging.WARNING)
    return lg


def flat_net(edge: float, mesh: float, **kw) -> HeldNet:
    """A flat taut traction net of the paper's rope (E = 1 MPa, ρ = 1000 kg/m³, d = 4.5 mm)."""
    cfg = TractionNet(edge_length=edge, mesh_size=mesh, rope_diameter=4.5e-3, corner_mass=kw.pop("corner_mass", 1e-3),
                      **kw)
    return held_net(cfg, NetSource.flat_taut, None)


def moved(net: HeldNet, x: np.ndarray) -> HeldNet:
    """The same net held at other positions x [m] (n, 3)."""
    return HeldNet(net.model, np.asarray(x, dtype=float), net.rest_length, net.node_radius, net.rope_radius,
                   net.rope_modulus, net.rope_density, net.source)


@pytest.fixture(scope="session")
def scenes():
    """The scene helpers of this module (``scenes.flat_net``, ``scenes.moved``)."""
    import types

    return types.SimpleNamespace(flat_net=flat_net, moved=moved)
