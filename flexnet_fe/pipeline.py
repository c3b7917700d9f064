"""Run a case's stages into a run directory (DESIGN.md §3) and keep ``status.json`` honest.

``run_dir/``
    ``resolved.json``  the validated config actually used (defaults filled in), versions, case hash
    ``status.json``    per stage: pending | running | done | failed (+ error); atomic writes
    ``summary.json``   the headline numbers, one section per completed stage
    ``<stage>/``       the stage's own files (history.csv, fields, plots, log.txt)

A stage that fails leaves ``status.json`` saying which and why; the files of the stages before it
stay; its own section is absent from ``summary.json``. Re-running a stage deletes its folder first.
A later stage may reuse an earlier stage's results from a previous run only when that run used the
same resolved case (same hash).
"""

from __future__ import annotations

import logging
import platform
import shutil
import time
from datetime import datetime, timezone
from pathlib import Path
from typing import Callable

from flexnet_fe import __version__
from flexnet_fe.config import STAGE_ORDER, STAGE_SECTIONS, Case, Stage, case_hash, resolved_dict
from flexnet_fe.errors import CaseError, FlexnetError
from flexnet_fe.io import atomic_write_json, read_json
from flexnet_fe.runs import StageContext

LOG = logging.getLogger("flexnet")

# Which earlier stage's outputs a stage reads (when the case asks for it).
def _needs(case: Case, stage: Stage) -> tuple[Stage, ...]:
    if stage is Stage.collide:
        return (Stage.deploy,) if case.collide.net_source.value == "deploy_max_area" else ()
    if stage is Stage.shell:
        return (Stage.collide,)
    if stage is Stage.flight:
        return (Stage.shell,) if case.flight.damage_from_shell else ()
    return ()


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="seconds")


def _versions() -> dict[str, str]:
    import numpy
    out = {"flexnet_fe": __version__, "python": platform.python_version(), "numpy": numpy.__version__}
    for mod in ("numba", "scipy", "pydantic", "dolfinx", "gmsh"):
        try:
            out[mod] = str(__import__(mod).__version__)
        except Exception:  # not installed or not importable: record that, don't fail the run
            out[mod] = "unavailable"
    return out


class _Status:
    """status.json, rewritten atomically on every change."""

    def __init__(self, path: Path, case: Case, digest: str):
        self.path = path
        old = read_json(path) if path.is_file() else {}
        stages = old.get("stages", {}) if old.get("case_hash") == digest else {}
        self.data = {"case": case.case.name, "case_hash": digest, "stages": {
            s.value: stages.get(s.value, {"state": "pending"}) for s in STAGE_ORDER}}
        self.save()

    def state(self, stage: Stage) -> str:
        return self.data["stages"][stage.value]["state"]

    def set(self, stage: Stage, **fields) -> None:
        self.data["stages"][stage.value] = fields
        self.save()

    def save(self) -> None:
        atomic_write_json(self.path, self.data)


def _stage_logger(stage_dir: Path, stage: Stage) -> tuple[logging.Logger, logging.Handler]:
    log = logging.getLogger(f"flexnet.{stage.value}")
    handler = logging.FileHandler(stage_dir / "log.txt", mode="w")
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
    log.addHandler(handler)
    return log, handler


def run_case(case: Case, case_dir: Path, run_dir: Path, stages: list[Stage] | None = None,
             stage_funcs: dict[Stage, Callable[[StageContext], dict]] | None = None) -> dict:
    """Run ``stages`` (default: the case's own list) in pipeline order into ``run_dir``.

    Returns the summary dict. Raises the stage's error after recording it in status.json.
    """
    from flexnet_fe.stages import STAGE_FUNCS

    funcs = stage_funcs or STAGE_FUNCS
    wanted = sorted(set(stages or case.case.stages), key=STAGE_ORDER.index)
    for stage in wanted:
        missing = [t for t in STAGE_SECTIONS[stage] if getattr(case, t) is None]
        if missing:
            raise CaseError("--stages", stage.value, f"the case has no [{missing[0]}] table, which this stage needs")
    run_dir = Path(run_dir)
    run_dir.mkdir(parents=True, exist_ok=True)
    digest = case_hash(case)
    atomic_write_json(run_dir / "resolved.json", {
        "case": resolved_dict(case), "case_dir": str(case_dir), "case_hash": digest,
        "versions": _versions(), "written": _now()})
    status = _Status(run_dir / "status.json", case, digest)
    summary_path = run_dir / "summary.json"
    summary = read_json(summary_path) if summary_path.is_file() else {}
    summary = {k: v for k, v in summary.items() if status.data["stages"].get(k, {}).get("state") == "done"}

    for stage in wanted:
        for need in _needs(case, stage):
            if need not in wanted and status.state(need) != "done":
                raise FlexnetError(f"stage '{stage.value}' needs the results of stage '{need.value}' "
                                   f"for this case in {run_dir}: run with --stages {need.value},{stage.value}")
    for stage in wanted:
        stage_dir = run_dir / stage.value
        if stage_dir.exists():
            shutil.rmtree(stage_dir)
        stage_dir.mkdir(parents=True)
        summary.pop(stage.value, None)
        atomic_write_json(summary_path, summary)
        status.set(stage, state="running", started=_now())
        log, handler = _stage_logger(stage_dir, stage)
        t0 = time.perf_counter()
        try:
            LOG.info("stage %s: running → %s", stage.value, stage_dir)
            section = funcs[stage](StageContext(case, case_dir, run_dir, stage_dir, log))
        except BaseException as err:
            reason = "interrupted" if isinstance(err, KeyboardInterrupt) else (str(err) or type(err).__name__)
            log.error("stage %s failed: %s", stage.value, reason)
            status.set(stage, state="failed", error=reason, started=status.data["stages"][stage.value]["started"],
                       finished=_now(), wall_s=time.perf_counter() - t0)
            raise
        finally:
            log.removeHandler(handler)
            handler.close()
        wall = time.perf_counter() - t0
        summary[stage.value] = section
        atomic_write_json(summary_path, summary)
        status.set(stage, state="done", started=status.data["stages"][stage.value]["started"],
                   finished=_now(), wall_s=wall)
        LOG.info("stage %s: done in %.1f s", stage.value, wall)
    return summary
