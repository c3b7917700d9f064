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


class RunDirError(FlexnetError):
    """The run directory cannot be used: locked by another run, not a run directory, unsafe
    name. Nothing was written. Exit code 2 (like bad input: the command line must change)."""

    exit_code = 2


class RunIOError(FlexnetError):
    """An operating-system I/O error (disk full, read-only, permission): names the path and the
    errno. Exit code 74 (``EX_IOERR`` of sysexits.h)."""

    exit_code = 74

    def __init__(self, err: OSError, doing: str = "", where: str | None = None):
        import errno as _errno

        self.errno = err.errno
        name = _errno.errorcode.get(err.errno or 0, str(err.errno))
        path = err.filename or (f"a file in {where}" if where else "(path not reported by the system)")
        what = f" while {doing}" if doing else ""
        super().__init__(f"{path}: {err.strerror or err} ({name}){what}")


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM arrived. Subclass of KeyboardInterrupt so that code that already
    handles Ctrl-C handles SIGTERM the same way. The process exits with 128 + ``signum``."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


class StageInterrupted(FlexnetError):
    """A stage was interrupted by a signal; status.json says ``interrupted``. The message is the
    one line the user sees; ``exit_code`` is 128 + signal number (130 for SIGINT, 143 for SIGTERM)."""

    def __init__(self, stage: str, signum: int, upto_s: float | None, where: str):
        self.stage, self.signum, self.upto_s = stage, signum, upto_s
        self.exit_code = 128 + signum
        kept = (f"outputs up to t = {upto_s:.6g} s kept in {where}" if upto_s is not None
                else f"no stage output written yet; earlier stages kept in {where}")
        super().__init__(f"interrupted during {stage}; {kept}")
