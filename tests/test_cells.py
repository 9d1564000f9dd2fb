"""grading/cells.py's time limit: the notebook's cells get CPU seconds, so a busy machine (or a
cell that waits a little) stops no honest notebook; held up CELLS_BUSY times as long, they stop with
the words for what happened. In a fresh process: the cells run in IPython's shell."""
import json
import subprocess
import sys

import pytest

from ikteach.course.grading.remote import _used
from ikteach.course.grading.time_limit import CELLS_BUSY

RUN = """
import json, sys
from ikteach.course.grading import cells
sent = []
done = cells.run(cells.shell(), json.loads(sys.argv[1]), sent.append, float(sys.argv[2]))
print(json.dumps([done, sent]))
"""


def run_cells(sources, timeout):
    argv = [json.dumps(list(enumerate(sources, 1))), str(timeout)]
    out = subprocess.run([sys.executable, "-c", RUN, *argv], capture_output=True, text=True,
                         timeout=120, check=True)
    return json.loads(out.stdout.splitlines()[-1])


def test_a_wait_shorter_than_busy_times_the_limit_is_not_stopped():
    done, sent = run_cells(["import time\ntime.sleep(0.8)", "x = 1"], timeout=0.4)
    assert done is True and {"cell": 2} in sent, sent


@pytest.mark.parametrize("source, words", [
    ("while True:\n    pass", "stopped after 0."),
    ("import time\ntime.sleep(60)", "this machine is busy (or the notebook waits)"),
])
def test_cells_past_their_cpu_time_or_held_up_are_stopped_with_why(source, words):
    done, sent = run_cells(["x = 1", source, "y = 2"], timeout=0.3)
    assert done == 2, sent
    stopped = next(m for m in sent if "stopped" in m)
    cpu, wall = stopped["used"]
    assert (cpu >= 0.3) if "while" in source else (wall >= CELLS_BUSY * 0.3 and cpu < 0.3)
    assert words in _used(stopped, 0.3), _used(stopped, 0.3)
