"""Shared helpers for the shell tests: tilted test plates, serial static solves."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import sparse
from scipy.sparse import linalg as sla

from flexnet_fe.shell.explicit import ShellOperator

# A plane tilted in all three axes, so the manifold-in-3-D path is exercised.
A1 = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
_a2 = np.array([0.0, 0.6, 0.8]) - np.dot([0.0, 0.6, 0.8], A1) * A1
A2 = _a2 / np.linalg.norm(_a2)
ORIGIN = np.array([-0.3, 0.2, 0.1])


def scipy_matrix(op: ShellOperator) -> sparse.csr_matrix:
    """The operator's K as a scipy CSR matrix (serial)."""
    K = op.K.convert("aij")
    ai, aj, av = K.getValuesCSR()
    return sparse.csr_matrix((av, aj, ai), shape=K.getSize())


def static_solve(op: ShellOperator, f: np.ndarray, u_fixed: np.ndarray | None = None) -> np.ndarray:
    """Solve K u = f on the free DOFs (M⁻¹ > 0) with u = u_fixed on the fixed ones (serial)."""
    K = scipy_matrix(op)
    free = op.minv > 0
    u = np.zeros(op.n_owned) if u_fixed is None else np.where(free, 0.0, u_fixed)
    rhs = f[free] - K[free][:, ~free] @ u[~free]
    u[free] = sla.spsolve(K[free][:, free].tocsc(), rhs)
    return u


def local_coords(x: np.ndarray) -> np.ndarray:
    """In-plane coordinates (s1, s2) [m] of points x (n, 3) of the tilted test plane."""
    r = x - ORIGIN
    return np.column_stack([r @ A1, r @ A2])


@pytest.fixture(autouse=True, scope="session")
def _quiet_logs():
    import logging
    logging.getLogger("UFL").setLevel(logging.ERROR)
    logging.getLogger("FFCX").setLevel(logging.ERROR)
    logging.getLogger().setLevel(logging.WARNING)
