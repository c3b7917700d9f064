"""Progress bars: shown on a terminal, silent in CI or when output is not a TTY."""

from __future__ import annotations

import logging
import os
import sys

from tqdm.auto import tqdm


def progress_enabled() -> bool:
    return sys.stderr.isatty() and not os.environ.get("CI") and not os.environ.get("FLEXNET_NO_PROGRESS")


def progress_bar(total: float, desc: str, unit: str = "step") -> tqdm:
    """A tqdm bar (context manager); call ``bar.update(n)`` from the stage's outer loop."""
    return tqdm(total=total, desc=desc, unit=unit, disable=not progress_enabled(), leave=False,
                dynamic_ncols=True)


def setup_logging(level: int = logging.INFO) -> None:
    """Console logging of the ``flexnet`` logger (its own stderr handler, no propagation).

    dolfinx calls logging.basicConfig() on import, and ffcx then logs every JIT compile to the
    root logger: give the root a quiet handler first (basicConfig is then a no-op). Called by
    the CLI and by every sweep worker process."""
    root = logging.getLogger()
    if not root.handlers:
        root.addHandler(logging.NullHandler())
    root.setLevel(logging.WARNING)
    log = logging.getLogger("flexnet")
    log.setLevel(level)
    log.propagate = False
    console = [h for h in log.handlers if getattr(h, "flexnet_console", False)]
    if console:  # called again in one process (tests, workers): follow the current sys.stderr
        console[0].stream = sys.stderr  # (setStream would flush the old, maybe closed, stream)
        return
    h = logging.StreamHandler(sys.stderr)
    h.flexnet_console = True
    h.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
    log.addHandler(h)
