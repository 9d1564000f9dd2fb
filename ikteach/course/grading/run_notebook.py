"""Run a student's notebook for its outputs, errors and notes (never for marks); runs inside
the sandbox as a script, so it imports nothing from ikteach.

    python run_notebook.py NOTEBOOK TIMEOUT_S REPORT_FD

Every code cell runs in one kernel under the notebook's time limit, except cells that only call
ik.check (the grader runs the checks itself, elsewhere). A cell that runs past the limit is
interrupted; a kernel that dies ends the run. Writes one JSON line to REPORT_FD (a pipe only the
grader reads): {"errors": [...], "notes": [...]}.
"""
import json
import logging
import os
import re
import sys
import time

MAX_TEXT = 300  # characters of an error message kept


def only_checks(source):
    """A cell that only calls ik.check.<name>(...) (the template's check cells)."""
    lines = [l for l in source.splitlines() if l.strip() and not l.strip().startswith("#")]
    return bool(lines) and all(re.match(r"\s*ik\.check\.\w+\(.*\)\s*$", l) for l in lines)


def error_lines(cells):
    """'cell k raised Name: value' for the cells that ended in an error."""
    lines = []
    for index, cell in enumerate(cells):
        for out in cell.get("outputs", []) if cell.get("cell_type") == "code" else []:
            if out.get("output_type") == "error":
                value = str(out.get("evalue", "")).splitlines()
                lines.append(f"cell {index + 1} raised {str(out.get('ename'))[:80]}"
                             f"{': ' + value[0][:MAX_TEXT] if value and value[0] else ''}")
    return lines


def run(path, timeout):
    # jsonschema (under nbformat) imports rfc3987_syntax where installed, which builds a
    # grammar at import: 1.1 s of every notebook's run, for an "iri" format no notebook uses
    sys.modules.setdefault("rfc3987_syntax", None)
    import nbformat
    from jupyter_core.utils import ensure_async, run_sync
    from nbclient import NotebookClient
    from nbclient.exceptions import CellTimeoutError, DeadKernelError

    logging.getLogger("asyncio").setLevel(logging.CRITICAL)
    book = nbformat.read(path, as_version=4)
    notes = []
    client = NotebookClient(book, timeout=timeout, kernel_name="python3", allow_errors=True,
                            interrupt_on_timeout=False, shutdown_kernel="immediate",
                            record_timing=False,
                            resources={"metadata": {"path": os.path.dirname(path)}})
    deadline = time.monotonic() + timeout
    with client.setup_kernel():
        for index, cell in enumerate(book.cells):
            if cell.cell_type != "code" or only_checks(cell.source):
                continue
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                notes.append(f"time limit of {timeout:g} s reached: cells from cell "
                             f"{index + 1} on were not run")
                break
            client.timeout = int(max(1, remaining))
            try:
                client.execute_cell(cell, index)
            except CellTimeoutError:
                notes.append(f"cell {index + 1} did not finish within the notebook's time "
                             f"limit ({timeout:g} s)")
                try:
                    run_sync(ensure_async)(client.km.interrupt_kernel())
                except Exception:
                    pass
                time.sleep(1.0)
            except DeadKernelError:
                notes.append(f"the kernel died in cell {index + 1}")
                break
            finally:
                for out in cell.get("outputs", []):  # keep memory bounded: texts not needed
                    out.pop("text", None)
                    out.pop("data", None)
    return {"errors": error_lines(book.cells), "notes": notes}


def main(argv):
    path, timeout, fd = argv[0], float(argv[1]), int(argv[2])
    report = os.fdopen(fd, "w")
    try:
        result = run(path, timeout)
    except Exception as exc:  # e.g. not a notebook: the grader says so from the file itself
        result = {"errors": [], "notes": [f"the notebook could not be run: "
                                          f"{type(exc).__name__}: {str(exc)[:MAX_TEXT]}"]}
    report.write(json.dumps(result) + "\n")
    report.flush()


if __name__ == "__main__":
    main(sys.argv[1:])
