"""Errors the user sees as one clear line (never a traceback)."""

from __future__ import annotations


class FlexnetError(Exception):
    """Base class: the CLI prints ``str(err)`` on one line and exits with ``exit_code``."""

    exit_code = 1


class CaseError(FlexnetError):
    """Bad input: names the file, the dotted field path and the reason. Exit code 2."""

    exit_code = 2

    def __init__(self, file: str, field: str, reason: str):
        self.file, self.field, self.reason = str(file), field, reason
        where = f"{self.file}: {field}" if field else self.file
        super().__init__(f"{where}: {reason}")


class NumericalError(FlexnetError):
    """A numerical blow-up (NaN, energy growth, tunnelling...) with what caused it. Exit code 3."""

    exit_code = 3
