"""A limit on CPU seconds for the checks' calls and a notebook's cells: load changes no mark."""
import contextlib
import signal
import threading
import time

CELLS_BUSY = 5  # wall s per CPU s of a notebook's cells' limit: then they count as held up


class TimeLimit(BaseException):
    """(CPU s, wall s) used, raised in the student's code: its `except Exception` lets it pass."""


@contextlib.contextmanager
def time_limit(seconds, busy, clock=time.process_time):
    """At most `seconds` of CPU time (`clock`), checked by SIGALRM in the main thread (elsewhere
    no limit); code held up `busy` times as long in wall time (a busy machine, or code that
    waits) stops too."""
    if (threading.current_thread() is not threading.main_thread()
            or not hasattr(signal, "setitimer")):
        yield
        return
    cpu, wall = clock(), time.monotonic()

    def _handler(signum, frame):
        used, waited = clock() - cpu, time.monotonic() - wall
        if used >= seconds or waited >= busy * seconds:
            raise TimeLimit(used, waited)
        left = min(seconds - used, busy * seconds - waited)
        signal.setitimer(signal.ITIMER_REAL, max(left, 0.05))

    previous = signal.signal(signal.SIGALRM, _handler)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
