"""Each lecture's Run All needs at most its budget of XLA programs (ikteach/course/warm.py:
BUDGETS; the table is in docs/maintainers.md), checked on nbval's own run of the lecture rather
than on a second one: before the first cell, nbval's kernel runs the counting cell of
`ikteach warm` (JAX's compile events, whether a program is compiled or loaded from the
persistent cache, so the count depends neither on the cache nor on the machine's speed); after
the last cell, a count over the budget fails that cell's teardown. Registered by conftest.py."""
from pathlib import Path

import pytest

from ikteach.course import warm


def _lecture(item):
    """The lecture a notebook cell of nbval's belongs to, or None."""
    path = Path(str(item.fspath))
    if path.suffix != ".ipynb" or path.parent.name != "notebooks" or not hasattr(item, "cell"):
        return None
    return path.stem if path.stem in warm.BUDGETS else None


def run_source(kernel, source, timeout=120):
    """Run `source` in nbval's kernel between two cells; returns what it printed."""
    msg_id = kernel.execute_cell_input(source, allow_stdin=False)
    kernel.await_reply(msg_id, timeout=timeout)
    printed = []
    while True:
        msg = kernel.get_message("iopub", timeout=timeout)
        if msg["parent_header"].get("msg_id") != msg_id:
            continue  # not ours (nbval skips them too)
        if msg["msg_type"] == "stream":
            printed.append(msg["content"]["text"])
        elif msg["msg_type"] == "error":
            raise RuntimeError("\n".join(msg["content"]["traceback"]))
        elif msg["msg_type"] == "status" and msg["content"]["execution_state"] == "idle":
            return "".join(printed)


def over_budget(name, counts):
    """The failure message for a lecture's counts, or None within its budget."""
    budget = warm.BUDGETS[name]
    if 0 < counts["programs"] <= budget:
        return None
    heaviest = sorted(counts["by_name"].items(), key=lambda kv: -kv[1][0])[:10]
    return (f"{name}: its Run All needed {counts['programs']} XLA programs, its budget is "
            f"{budget} (ikteach/course/warm.py: BUDGETS); most by name: {heaviest}")


class LectureBudgets:
    @pytest.hookimpl(wrapper=True)
    def pytest_runtest_setup(self, item):
        result = yield  # nbval's kernel starts in the notebook's setup, with the first cell
        notebook = item.parent
        if _lecture(item) and not getattr(notebook, "_ikteach_counting", False):
            notebook._ikteach_counting = True
            run_source(notebook.kernel, warm.COUNT_CELL)
        return result

    @pytest.hookimpl(wrapper=True)
    def pytest_runtest_teardown(self, item, nextitem):
        name, notebook = _lecture(item), item.parent
        message = None
        if (name and getattr(notebook, "_ikteach_counting", False) and notebook.kernel.is_alive()
                and (nextitem is None or nextitem.parent is not notebook)):  # its last cell
            counts = warm.read_counts(run_source(notebook.kernel, warm.REPORT_CELL))
            message = over_budget(name, counts)
        result = yield  # then nbval stops the kernel
        if message:
            pytest.fail(message, pytrace=False)
        return result
