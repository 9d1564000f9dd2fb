"""heap.settle: what is alive is frozen out of the cycle collector's walks, later cycles are
still collected, and what is left at exit is frozen once more (one exit hook however often)."""
import subprocess
import sys


def _run(code):
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.split()


def test_settle_freezes_the_heap_and_later_cycles_are_still_collected():
    code = """
import atexit, gc
from ikteach import heap
before = atexit._ncallbacks()
heap.settle()
frozen = gc.get_freeze_count()
class Node: pass
gc.collect()
a, b = Node(), Node(); a.other, b.other = b, a
heap.settle()  # again (the setup cell run twice): the cycle made since is not frozen
del a, b
print(frozen > 1000, gc.get_freeze_count() == frozen, atexit._ncallbacks() - before,
      gc.collect() >= 2)
"""
    assert _run(code) == ["True", "True", "1", "True"]


def test_what_is_left_at_exit_is_frozen_before_shutdown_sweeps_it():
    code = """
import atexit, gc
atexit.register(lambda: print(len(gc.get_objects())))  # runs after settle's hook
from ikteach import heap
heap.settle()
kept = [[i] for i in range(10_000)]   # made after settle: tracked until the exit hook
print(len(gc.get_objects()) >= 10_000)
"""
    assert _run(code) == ["True", "0"]  # nothing left for the shutdown to walk


def test_setup_settles_the_heap():
    code = ("import gc, ikteach as ik; ik.notebook.setup(); "
            "print(gc.get_freeze_count() > 10_000)")
    assert _run(code)[-1] == "True"
