"""Progress bars: shown on a terminal, silent in CI or when output is not a TTY."""

from __future__ import annotations

import os
import sys

from tqdm.auto import tqdm


def progress_enabled() -> bool:
    return sys.stderr.isatty() and not os.environ.get("CI") and not os.environ.get("FLEXNET_NO_PROGRESS")


def progress_bar(total: float, desc: str, unit: str = "step") -> tqdm:
    """A tqdm bar (context manager); call ``bar.update(n)`` from the stage's outer loop."""
    return tqdm(total=total, desc=desc, unit=unit, disable=not progress_enabled(), leave=False,
                dynamic_ncols=True)
