"""What this process may use: its cores, and whether it is a rank of an mpirun job."""

from __future__ import annotations

import os

MPI_LAUNCH_VARS = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS")
"""Environment variables set by the MPI launchers (Open MPI, MPICH/Hydra, PMIx)."""


def cpu_count() -> int:
    """Cores this process may run on (its affinity mask, where the system has one)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def launched_by_mpirun() -> bool:
    """True when this process is a rank started by mpirun — not a plain process that initialised MPI
    for itself, as importing dolfinx does."""
    return any(k in os.environ for k in MPI_LAUNCH_VARS)
