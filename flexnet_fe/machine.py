"""What this process may use: its cores, and whether it is a rank of an mpirun job."""

from __future__ import annotations

import os

MPI_LAUNCH_VARS = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS")
"""Environment variables set by the MPI launchers (Open MPI, MPICH/Hydra, PMIx)."""


def cpu_count() -> int:
    """Cores this process may run on (its affinity mask, where the system has one)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


SINGLETON = ("OMPI_MCA_ess", "singleton")
"""The variable Open MPI sets when a plain process initialises MPI for itself (a *singleton*, as
importing dolfinx does), with the value it sets. The singleton's ``setenv`` also leaves PMIX_RANK
and some 25 more OMPI_*, ORTE_* and PMIX_* variables, which every process it starts afterwards
inherits (pytest-xdist's workers, when a conftest of the arguments' folders imports dolfinx)."""


def launched_by_mpirun() -> bool:
    """True when this process is a rank started by mpirun — not a plain process that initialised MPI
    for itself, as importing dolfinx does, nor a child of one (which inherits its PMIX_RANK)."""
    if os.environ.get(SINGLETON[0]) == SINGLETON[1]:
        return any(k in os.environ for k in MPI_LAUNCH_VARS if k != "PMIX_RANK")
    return any(k in os.environ for k in MPI_LAUNCH_VARS)


def launcher_env(env: dict[str, str]) -> dict[str, str]:
    """``env`` for starting mpirun from this process: without the variables an MPI singleton left
    (:data:`SINGLETON`), with which Open MPI's mpirun exits 1 without a word; ``env`` itself when
    it has none."""
    if env.get(SINGLETON[0]) != SINGLETON[1]:
        return dict(env)
    return {k: v for k, v in env.items() if not k.startswith(("OMPI_", "ORTE_", "PMIX_"))}
