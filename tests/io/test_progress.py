"""Progress on stderr (io/progress.py): a bar on a terminal, plain lines in a log."""

from __future__ import annotations

import io

from tissuesim.io import progress
from tissuesim.io.progress import LogLines, progress_bar


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_log_gets_a_line_about_every_tenth_of_the_run_and_no_carriage_returns():
    log = io.StringIO()
    bar = progress_bar(200, True, log)
    assert isinstance(bar, LogLines)
    for k in range(200):
        bar.set_postfix(t=f"{0.01 * (k + 1):.4g}", newton=3)
        bar.update(1)
    bar.close()
    lines = log.getvalue().splitlines()
    assert len(lines) == 10 and "\r" not in log.getvalue()
    assert lines[0].startswith("tissuesim: step 20/200 (10 %),") and lines[0].endswith("newton=3")
    assert lines[-1].startswith("tissuesim: step 200/200 (100 %)") and "t=2" in lines[-1]


def test_a_slow_run_gets_a_line_every_interval(monkeypatch):
    log = io.StringIO()
    clock = iter(range(0, 1000, 40))  # 40 s per step
    monkeypatch.setattr(progress.time, "perf_counter", lambda: float(next(clock)))
    bar = progress_bar(1000, True, log)
    for _ in range(3):
        bar.update(1)
    assert len(log.getvalue().splitlines()) == 3  # past LOG_INTERVAL_S every time


def test_a_terminal_gets_the_bar_and_quiet_gets_nothing():
    bar = progress_bar(5, True, Terminal())
    assert type(bar).__name__ == "tqdm"
    bar.close()
    quiet = io.StringIO()
    bar = progress_bar(5, False, quiet)
    for _ in range(5):
        bar.update(1)
    assert quiet.getvalue() == ""
