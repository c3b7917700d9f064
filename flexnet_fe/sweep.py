"""Batches and sweeps: many runs, one table — in parallel, resumable.

A sweep is a cartesian product of ``--set``-style overrides of one base case. Each variant runs
into its own run directory ``<out>/<label>/``, the label made from its parameters
(``rope_diameter-3e-3_air-true``). ``<out>/sweep.csv`` (one row per finished variant: label,
parameters, the flattened summary, ``error``) is rewritten atomically each time a variant
finishes, so a killed sweep keeps the rows of the variants it finished.

Re-running the same sweep skips every variant whose run directory says all its stages are done
with the same inputs (``--force`` redoes them); an interrupted variant resumes at the stage that
was interrupted (the pipeline skips its done stages).

Engines: ``-j N`` runs N variants at a time in a local process pool (``multiprocessing``,
spawned workers); ``--executor mpi`` hands the variants to ``mpi4py.futures.MPIPoolExecutor``,
for a cluster: ``mpiexec -n 9 python -m mpi4py.futures -m flexnet_fe.cli sweep … --executor mpi``
(one manager, eight workers; under Slurm: ``srun -n 9 python -m mpi4py.futures …``). Each variant
runs serially in one worker. A case's own built-in sweep (``[flight.sweep]``) is not run inside
the variants: a sweep point is one engagement.
"""

from __future__ import annotations

import csv
import hashlib
import io
import itertools
import logging
import multiprocessing
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

from flexnet_fe.config import load_case
from flexnet_fe.errors import CaseError, FlexnetError, StageInterrupted
from flexnet_fe.io import atomic_write_text, read_json
from flexnet_fe.progress import progress_bar
from flexnet_fe.runs import MAX_NAME, STATUS, SUMMARY, interrupt_handled

LOG = logging.getLogger("flexnet")

LABEL, ERROR = "label", "error"
"""Fixed columns of the table (the report reads ``label`` and ``error``)."""


@dataclass(frozen=True)
class Variant:
    """One run of a sweep or batch: its folder name, case file and overrides."""

    label: str
    case_path: Path
    overrides: tuple[str, ...]
    params: tuple[tuple[str, str], ...] = ()
    sweep_point: bool = True
    """True: a point of a sweep (the case's own ``[flight.sweep]`` is dropped); False: a batch
    case, run as it is."""


def parse_axis(text: str) -> tuple[str, list[str]]:
    """``net.rope_diameter=2e-3,3e-3`` → ("net.rope_diameter", ["2e-3", "3e-3"])."""
    if "=" not in text:
        raise CaseError("--vary", text, "expected key=v1,v2,...")
    key, values = text.split("=", 1)
    vals = [v.strip() for v in values.split(",") if v.strip()]
    if not vals:
        raise CaseError("--vary", key, "no values")
    if len(set(vals)) != len(vals):
        raise CaseError("--vary", key.strip(), "a value is listed twice")
    return key.strip(), vals


def sweep_points(axes: list[tuple[str, list[str]]]) -> list[list[str]]:
    """Cartesian product of the axes as lists of ``key=value`` overrides."""
    return [[f"{k}={v}" for (k, _), v in zip(axes, combo)]
            for combo in itertools.product(*[vals for _, vals in axes])]


def safe_name(text: str) -> str:
    """A folder name from free text: letters, digits, ``_ . -`` only, not starting with ``.``,
    at most MAX_NAME characters (longer ones end with an 8-character hash to stay unique)."""
    name = re.sub(r"[^A-Za-z0-9_.-]+", "-", text).strip("-") or "variant"
    if name.startswith("."):
        name = "v" + name
    if len(name) > MAX_NAME:
        digest = hashlib.sha256(text.encode()).hexdigest()[:8]
        name = name[:MAX_NAME - 9] + "-" + digest
    return name


def variant_label(point: list[str], axes: list[tuple[str, list[str]]]) -> str:
    """``["net.rope_diameter=3e-3", "deploy.air=true"]`` → ``rope_diameter-3e-3_air-true`` (the
    full dotted key where two axes share their last part)."""
    lasts = [k.rsplit(".", 1)[-1] for k, _ in axes]
    parts = []
    for (key, _), text in zip(axes, point):
        short = key.rsplit(".", 1)[-1]
        value = text.split("=", 1)[1].strip().strip("'\"")
        parts.append(f"{short if lasts.count(short) == 1 else key}-{value}")
    return safe_name("_".join(parts))


def sweep_variants(case_path: Path, base: list[str], axes: list[tuple[str, list[str]]]) -> list[Variant]:
    out = [Variant(variant_label(pt, axes), Path(case_path), tuple(base) + tuple(pt),
                   tuple((o.split("=", 1)[0], o.split("=", 1)[1]) for o in pt)) for pt in sweep_points(axes)]
    labels = [v.label for v in out]
    if len(set(labels)) != len(labels):
        dup = next(lab for lab in labels if labels.count(lab) > 1)
        raise CaseError("--vary", dup, "two variants would share this folder name; use distinct values")
    return out


def flatten(summary: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested summary → {"deploy.max_area_m2": ..., ...} (scalars only)."""
    out: dict[str, Any] = {}
    for k, v in summary.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        elif isinstance(v, (int, float, str, bool)) or v is None:
            out[key] = v
    return out


def without_builtin_sweep(case):
    """The case without its ``[flight.sweep]``: a sweep point runs one engagement."""
    if getattr(case, "flight", None) is not None and case.flight.sweep is not None:
        return case.model_copy(update={"flight": case.flight.model_copy(update={"sweep": None})})
    return case


def variant_done(run_dir: Path, case) -> bool:
    """All the case's stages are done in ``run_dir`` with the inputs of ``case``."""
    from flexnet_fe.pipeline import stage_hashes

    try:
        stages = read_json(run_dir / STATUS)["stages"]
    except (OSError, ValueError, KeyError):
        return False
    hashes = stage_hashes(case)
    return all(stages.get(s.value, {}).get("state") == "done"
               and stages[s.value].get("input_hash") == hashes.get(s) for s in case.case.stages)


def run_or_reuse(variant: Variant, out: str, force: bool = False) -> dict[str, Any]:
    """Run one variant into ``out/label``, or reuse that run directory when all its stages are
    done with the same inputs (unless ``force``); returns its summary. Errors propagate."""
    from flexnet_fe.pipeline import run_case

    run_dir = Path(out) / variant.label
    case, case_dir = load_case(variant.case_path, list(variant.overrides))
    if variant.sweep_point:
        case = without_builtin_sweep(case)
    if not force and variant_done(run_dir, case):
        LOG.info("%s: done earlier with the same inputs, reused (--force redoes it)", variant.label)
        return read_json(run_dir / SUMMARY)
    return run_case(case, case_dir, run_dir, force=force, mpi=False)


def run_variant(variant: Variant, out: str, force: bool = False) -> dict[str, Any]:
    """Run (or reuse) one variant into ``out/label``; returns its table row. Errors become the
    row's ``error``; an interrupt propagates. Top-level so process pools can pickle it."""
    row: dict[str, Any] = {LABEL: variant.label, **dict(variant.params)}
    try:
        row.update(flatten(run_or_reuse(variant, out, force)))
        row[ERROR] = ""
    except StageInterrupted as err:
        LOG.error("%s: %s", variant.label, err)
        if multiprocessing.parent_process() is not None:
            # A pool worker told to stop (Pool.terminate sends SIGTERM): status.json already says
            # "interrupted"; end now — returning a row would block on the pool's dead result queue.
            logging.shutdown()
            os._exit(err.exit_code)
        raise
    except (FlexnetError, ArithmeticError, ValueError, RuntimeError, OSError) as err:
        LOG.error("%s: %s", variant.label, err)
        row[ERROR] = str(err) or type(err).__name__
    return row


def write_table(table: Path, rows: Iterable[dict[str, Any]]) -> None:
    """Rewrite the CSV table atomically (columns: label, parameters, outputs…, error)."""
    rows = list(rows)
    columns = list(dict.fromkeys(k for r in rows for k in r if k != ERROR)) + [ERROR]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns)
    w.writeheader()
    w.writerows(rows)
    atomic_write_text(table, buf.getvalue())


def run_many(variants: list[Variant], out: Path, table: Path, jobs: int = 1, force: bool = False,
             executor: str = "local") -> list[dict[str, Any]]:
    """Run every variant (``jobs`` at a time, or through ``mpi4py.futures`` when ``executor`` is
    "mpi"), rewriting ``table`` as each finishes. Returns the rows in variant order. On
    SIGINT/SIGTERM the workers are stopped, the table keeps the finished rows, and the
    interrupt propagates."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    order = {v.label: i for i, v in enumerate(variants)}
    done: dict[str, dict[str, Any]] = {}

    def finished(row: dict[str, Any]) -> None:
        done[row[LABEL]] = row
        write_table(table, sorted(done.values(), key=lambda r: order[r[LABEL]]))
        bar.update(1)

    with progress_bar(len(variants), "runs", unit="run") as bar:
        if executor == "mpi":
            _run_mpi(variants, out, force, finished)
        elif jobs <= 1:
            for v in variants:
                finished(run_variant(v, str(out), force))
        else:
            _run_pool(variants, out, force, jobs, finished)
    return [done[v.label] for v in variants]


def _run_pool(variants, out, force, jobs, finished) -> None:
    import multiprocessing as mp

    from flexnet_fe.progress import setup_logging

    pool = mp.get_context("spawn").Pool(jobs, initializer=setup_logging,
                                        initargs=(logging.getLogger("flexnet").getEffectiveLevel(),))
    try:
        results = [pool.apply_async(run_variant, (v, str(out), force)) for v in variants]
        pending = list(results)
        while pending:
            for r in [r for r in pending if r.ready()]:
                pending.remove(r)
                finished(r.get())
            if pending:
                pending[0].wait(0.2)
        pool.close()
    except BaseException as err:
        if isinstance(err, KeyboardInterrupt):
            interrupt_handled()
        _stop_workers()
        pool.terminate()
        raise
    finally:
        pool.join()


def _stop_workers(grace_s: float = 20.0) -> None:
    """SIGTERM to every worker (each records its running stage as interrupted and exits), then
    SIGKILL to any still alive after ``grace_s``: a worker that already finished its variant
    would otherwise block on the pool's closed result queue and ``Pool.terminate`` would wait."""
    import multiprocessing as mp

    workers = mp.active_children()
    for w in workers:
        w.terminate()
    for w in workers:
        w.join(grace_s / max(len(workers), 1))
        if w.is_alive():
            w.kill()


def _run_mpi(variants, out, force, finished) -> None:
    from concurrent.futures import as_completed

    from mpi4py.futures import MPIPoolExecutor

    with MPIPoolExecutor() as ex:
        futures = [ex.submit(run_variant, v, str(out), force) for v in variants]
        try:
            for f in as_completed(futures):
                finished(f.result())
        except BaseException:
            for f in futures:
                f.cancel()
            raise
