"""grading/cells.py's time limit: the notebook's cells get CPU seconds, so a busy machine (or a
cell that waits a little) stops no honest notebook; held up CELLS_BUSY times as long, they stop with
the words for what happened. In a fresh process: the cells run in IPython's shell. A case about
one limit moves the other out of reach, so that it holds on a busy machine too."""
import json
import subprocess
import sys

import pytest

from ikteach.course.grading.remote import _used
from ikteach.course.grading.time_limit import CELLS_BUSY

RUN = """
import json, sys
from ikteach.course.grading import cells
cells.CELLS_BUSY = float(sys.argv[3])
sent = []
done = cells.run(cells.shell(), json.loads(sys.argv[1]), sent.append, float(sys.argv[2]))
print(json.dumps([done, sent]))
"""


def run_cells(sources, timeout, busy=CELLS_BUSY):
    argv = [json.dumps(list(enumerate(sources, 1))), str(timeout), str(busy)]
    out = subprocess.run([sys.executable, "-c", RUN, *argv], capture_output=True, text=True,
                         timeout=120, check=True)
    return json.loads(out.stdout.splitlines()[-1])


def test_a_wait_shorter_than_busy_times_the_limit_is_not_stopped():
    done, sent = run_cells(["import time\ntime.sleep(0.8)", "x = 1"], timeout=0.4)
    assert done is True and {"cell": 2} in sent, sent


# a busy loop with the wall-clock limit out of reach (a loaded machine may give it little CPU);
# a sleep, which uses none, under the usual CELLS_BUSY
@pytest.mark.parametrize("source, busy, words", [
    ("while True:\n    pass", 1000, "stopped after 0."),
    ("import time\ntime.sleep(60)", CELLS_BUSY, "this machine is busy (or the notebook waits)"),
])
def test_cells_past_their_cpu_time_or_held_up_are_stopped_with_why(source, busy, words):
    done, sent = run_cells(["x = 1", source, "y = 2"], timeout=0.3, busy=busy)
    assert done == 2, sent
    stopped = next(m for m in sent if "stopped" in m)
    cpu, wall = stopped["used"]
    assert (cpu >= 0.3) if "while" in source else (wall >= CELLS_BUSY * 0.3 and cpu < 0.3)
    assert words in _used(stopped, 0.3), _used(stopped, 0.3)
