"""Small helper models for the net tests (built directly, so each test controls every input)."""

import numpy as np
import pytest

from flexnet_fe.net.topology import NetModel


def chain_model(x0, v0, mass, springs, rest, ea, damping=None, offset=None, diameter=1e-3,
                **hub) -> NetModel:
    """A NetModel from explicit arrays (no cells: area not used)."""
    springs = np.asarray(springs, dtype=np.int64)
    m = len(springs)
    return NetModel(
        kind="test", x0=np.asarray(x0, float), v0=np.asarray(v0, float), mass=np.asarray(mass, float),
        springs=springs, rest_length=np.broadcast_to(np.asarray(rest, float), (m,)).copy(),
        stiffness_ea=np.broadcast_to(np.asarray(ea, float), (m,)).copy(),
        damping=np.zeros(m) if damping is None else np.broadcast_to(np.asarray(damping, float), (m,)).copy(),
        slack_offset=np.zeros(m) if offset is None else np.broadcast_to(np.asarray(offset, float), (m,)).copy(),
        diameter=np.full(m, diameter), drag_free=np.zeros(len(mass), dtype=np.bool_),
        mass_nodes=np.zeros(0, dtype=np.int64), cells=np.zeros((0, 3), dtype=np.int64),
        boundary_loop=np.zeros(0, dtype=np.int64), **hub)


@pytest.fixture
def make_chain():
    return chain_model
