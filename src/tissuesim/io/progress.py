"""The run's progress on stderr: tqdm's bar on a terminal; elsewhere (a log file, a pipe, CI)
one plain line about every tenth of the run or every 30 s, whichever comes first, since a bar's
carriage returns flood a log with thousands of redrawn lines."""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

__all__ = ["note", "progress_bar", "set_quiet"]

#: at most this many seconds between two lines in a log
LOG_INTERVAL_S = 30.0
_quiet = False


def set_quiet(quiet: bool) -> None:
    """Whether ``note`` stays silent (the command line's ``--quiet``)."""
    global _quiet
    _quiet = bool(quiet)


def note(message: str) -> None:
    """One line for the user on stderr ("tissuesim: ..."), unless quiet."""
    if not _quiet:
        print(f"tissuesim: {message}", file=sys.stderr, flush=True)


def progress_bar(total: int, enabled: bool, file: TextIO | None = None) -> Any:
    """An object with tqdm's ``set_postfix(**values)``, ``update(n)`` and ``close()``."""
    file = sys.stderr if file is None else file
    if enabled and _is_terminal(file):
        from tqdm import tqdm

        return tqdm(total=total, file=file, unit="step")
    return LogLines(total, enabled, file)


def _is_terminal(file: TextIO) -> bool:
    try:
        return bool(file.isatty())
    except (AttributeError, ValueError):
        return False


class LogLines:
    """Progress as plain lines: "step 40/200 (20 %), 3.1 s, t=0.4, newton=3, minJ=0.98"."""

    def __init__(self, total: int, enabled: bool, file: TextIO) -> None:
        self.total, self.enabled, self.file = total, enabled, file
        self.n = 0
        self.postfix: dict[str, Any] = {}
        self.start = self.last = time.perf_counter()
        self.every = max(1, total // 10)

    def set_postfix(self, **values: Any) -> None:
        self.postfix = values

    def update(self, n: int = 1) -> None:
        self.n += n
        now = time.perf_counter()
        if self.n % self.every == 0 or self.n == self.total or now - self.last >= LOG_INTERVAL_S:
            self._line(now)

    def _line(self, now: float) -> None:
        self.last = now
        if not self.enabled:
            return
        share = f" ({100 * self.n // self.total} %)" if self.total else ""
        extra = "".join(f", {k}={v}" for k, v in self.postfix.items())
        print(
            f"tissuesim: step {self.n}/{self.total}{share}, {now - self.start:.1f} s{extra}",
            file=self.file,
            flush=True,
        )

    def close(self) -> None:
        pass
