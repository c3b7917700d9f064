"""Run directories: the contract between stages, reports, sweeps and tests (DESIGN.md §3).

A stage is a function ``run(ctx: StageContext) -> dict`` that writes its files into
``ctx.stage_dir`` and returns its section of ``summary.json`` (SI units, JSON-able values).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class StageContext:
    """What a stage gets.

    case      the validated case (``flexnet_fe.config.Case``)
    case_dir  folder of the case file; files named in the case resolve against it
    run_dir   the run directory (``runs/<name>/``); earlier stages' outputs are in its sub-folders
    stage_dir ``run_dir / <stage name>``, created empty for this stage
    log       a named logger that writes to ``stage_dir / "log.txt"`` (and the console)
    """

    case: Any
    case_dir: Path
    run_dir: Path
    stage_dir: Path
    log: logging.Logger

    def stage_output(self, stage: str) -> Path:
        """Folder of an earlier stage's outputs (it must have completed)."""
        return self.run_dir / stage
