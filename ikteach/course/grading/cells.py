"""A notebook's job, in a fresh child of the fork server (forkserver.py): its code cells run in
IPython's shell, in order, as a kernel runs them; then the checks call the functions those cells
left in the shell's namespace - the namespace the notebook built (top-level classes, constants
made in loops, module aliases, `from __future__` imports), not a re-reading of its source.

The grader sends one JSON line on REQUESTS: {"cells": [[number, source], ...], "graded": [names],
"timeout": s}. Cells that only call ik.check are skipped (the grader runs the checks itself).
Before each cell a line {"cell": N} goes to REPLIES, after a cell that raised {"error": "cell N
raised Name: value"}. The cells get `timeout` CPU seconds in all (CELLS_BUSY times as long
in wall time): then the running cell is interrupted (SIGALRM) and the rest skipped ({"stopped":
N, "used": [CPU s, wall s]}); a notebook that ignores the alarm is killed from outside by the
fork server and the grader. Then {"ready": ...} (remote.serve) and the calls. Code objects
compile as `<cell N>` (tracebacks and grading/own_code.py name them); a cell starting with
%%time or %%capture runs as its body (their own compile names it otherwise). Magics run as in a
kernel without a screen (`%matplotlib inline` draws into memory); shell lines (`!`, %pip,
%conda) are skipped, and a magic that fails is a note: the rest of its cell runs."""
import json
import os
import re

from .extract import cell_body
from .time_limit import CELLS_BUSY, TimeLimit, time_limit

MAX_TEXT = 300  # characters of an error message kept


def only_checks(source):
    """A cell that only calls ik.check.<name>(...) (the template's check cells)."""
    lines = [l for l in source.splitlines() if l.strip() and not l.strip().startswith("#")]
    return bool(lines) and all(re.match(r"\s*ik\.check\.\w+\(.*\)\s*$", l) for l in lines)


def error_line(number, exc):
    value = str(exc).splitlines()
    return (f"cell {number} raised {type(exc).__name__[:80]}"
            f"{': ' + value[0][:MAX_TEXT] if value and value[0] else ''}")


def shell():
    """IPython's shell, without history (no database, no thread); cells compile as <cell N>;
    `notes` collects the magics it skipped."""
    from IPython.core.interactiveshell import InteractiveShell
    from traitlets.config import Config

    class Shell(InteractiveShell):
        notes = []

        def enable_gui(self, gui=None):  # a kernel without a screen: no event loop to start
            pass

        def run_line_magic(self, magic_name, line, _stack_depth=1):
            if magic_name in ("pip", "conda", "mamba", "uv"):
                return self.system(f"%{magic_name} {line}", "")
            try:
                return super().run_line_magic(magic_name, line, _stack_depth + 1)
            except Exception as exc:
                why = str(exc).splitlines()[0][:200] if str(exc) else ""
                self.notes.append(f"`%{magic_name} {line}`"[:80] + " was skipped "
                                  f"({type(exc).__name__[:80]}: {why})")

        def system(self, cmd, mark="!"):
            self.notes.append(f"`{mark}{cmd}`"[:80] + " was skipped: the grader runs no shell "
                              "commands or installs")

    config = Config()
    config.HistoryManager.enabled = False
    instance = Shell.instance(config=config)
    instance.compile.get_code_name = lambda raw, transformed, number: f"<cell {number}>"
    return instance


def run(instance, cells, send, timeout):
    """Run the cells; True when all ran, else the number of the cell the time limit stopped."""
    try:
        with time_limit(timeout, CELLS_BUSY):
            for number, source in cells:
                if only_checks(source):
                    continue
                send({"cell": number})
                instance.execution_count = number  # the <cell N> name (get_code_name's number)
                result = instance.run_cell(cell_body(source), store_history=False)
                exc = result.error_before_exec or result.error_in_exec
                if isinstance(exc, TimeLimit):
                    send({"stopped": number, "used": exc.args})
                    return number
                if exc is not None:
                    send({"error": error_line(number, exc)})
                while instance.notes:
                    send({"error": f"cell {number}: {instance.notes.pop(0)}"})
    except TimeLimit as exc:  # between cells, or in IPython's own code
        send({"stopped": "the end", "used": exc.args})
        return False
    return True


def namespace(instance):
    """What the cells defined: the shell's namespace without IPython's own names."""
    hidden = instance.user_ns_hidden
    return {k: v for k, v in instance.user_ns.items()
            if k not in hidden and not re.fullmatch(r"_+|_[iho]+\d*|_dh|_ii+", k)}


def main(requests_fd, replies_fd):
    from . import remote

    requests = os.fdopen(requests_fd, "r", encoding="utf-8", errors="replace")
    replies = os.fdopen(replies_fd, "w")

    def send(message):
        replies.write(json.dumps(message) + "\n")
        replies.flush()

    setup = json.loads(requests.readline())
    instance = shell()
    run(instance, [(int(n), str(s)) for n, s in setup["cells"]], send,
        float(setup.get("timeout", 120.0)))
    remote.serve(namespace(instance), [str(n) for n in setup.get("graded", [])], requests,
                 send)
