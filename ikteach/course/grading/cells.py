"""Run a student's notebook cells for their errors and notes (never for marks), in a child of
the fork server (forkserver.py), with IPython's shell as a kernel would.

The grader sends one JSON line on REQUESTS: {"cells": [[cell number, source], ...]}. Every code
cell runs in order, except cells that only call ik.check (the grader runs the checks itself,
elsewhere). Before each cell a line {"cell": N} goes to REPLIES, after a cell that raised
{"error": "cell N raised Name: value"}, and {"done": true} at the end. The time limit is the
fork server's: it kills the whole job; the grader then knows from the last {"cell": N} which
cell did not finish.
"""
import json
import os
import re

MAX_TEXT = 300  # characters of an error message kept


def only_checks(source):
    """A cell that only calls ik.check.<name>(...) (the template's check cells)."""
    lines = [l for l in source.splitlines() if l.strip() and not l.strip().startswith("#")]
    return bool(lines) and all(re.match(r"\s*ik\.check\.\w+\(.*\)\s*$", l) for l in lines)


def error_line(number, exc):
    value = str(exc).splitlines()
    return (f"cell {number} raised {type(exc).__name__[:80]}"
            f"{': ' + value[0][:MAX_TEXT] if value and value[0] else ''}")


def run(cells, send):
    from IPython.core.interactiveshell import InteractiveShell
    from traitlets.config import Config

    config = Config()
    config.HistoryManager.enabled = False  # no database, no thread
    shell = InteractiveShell.instance(config=config)
    for number, source in cells:
        if only_checks(source):
            continue
        send({"cell": number})
        result = shell.run_cell(source, store_history=False)
        exc = result.error_before_exec or result.error_in_exec
        if exc is not None:
            send({"error": error_line(number, exc)})
    send({"done": True})


def main(requests_fd, replies_fd):
    with os.fdopen(requests_fd, "r", encoding="utf-8", errors="replace") as requests:
        setup = json.loads(requests.readline())
    replies = os.fdopen(replies_fd, "w")

    def send(message):
        replies.write(json.dumps(message) + "\n")
        replies.flush()

    run([(int(n), str(s)) for n, s in setup["cells"]], send)
