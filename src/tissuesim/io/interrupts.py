"""Interrupts around output that must be finished: SIGTERM (``kill``) ends a run as Ctrl-C does,
with status "interrupted", instead of killing it mid-write; a second Ctrl-C while the first is
being handled is ignored, and one that comes while the final summary of a completed run is
written waits until it is written.

Both only act in the main thread (Python delivers signals there); elsewhere they do nothing.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["deferred_interrupts", "interrupts_as_keyboard_interrupt"]

_SIGNALS = tuple(s for s in (signal.SIGINT, getattr(signal, "SIGTERM", None)) if s is not None)


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextmanager
def deferred_interrupts() -> Iterator[None]:
    """Hold SIGINT/SIGTERM while the block runs; raise KeyboardInterrupt after it if one came."""
    if not _main_thread():
        yield
        return
    received: list[int] = []
    previous = {s: signal.signal(s, lambda sig, frame: received.append(sig)) for s in _SIGNALS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    if received:
        raise KeyboardInterrupt(_name(received[0]))


@contextmanager
def interrupts_as_keyboard_interrupt() -> Iterator[None]:
    """In the block the first SIGINT or SIGTERM raises KeyboardInterrupt ("SIGTERM" for the
    latter, as Ctrl-C does for the former); later ones are ignored, so a second Ctrl-C cannot
    break off the handler that is recording how the run ended."""
    if not _main_thread():
        yield
        return
    stopping = [False]

    def on_signal(sig, frame):
        if stopping[0]:
            return
        stopping[0] = True
        raise KeyboardInterrupt(_name(sig))

    previous = {s: signal.signal(s, on_signal) for s in _SIGNALS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def _name(sig: int) -> str:
    return "SIGTERM" if sig == getattr(signal, "SIGTERM", None) else "KeyboardInterrupt"
