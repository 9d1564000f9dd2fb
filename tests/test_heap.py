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
from ikteach.course import heap
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
from ikteach.course import heap
heap.settle()
kept = [[i] for i in range(10_000)]   # made after settle: tracked until the exit hook
print(len(gc.get_objects()) >= 10_000)
"""
    assert _run(code) == ["True", "0"]  # nothing left for the shutdown to walk


def test_setup_settles_the_heap():
    code = ("import gc, ikteach as ik; ik.notebook.setup(); "
            "print(gc.get_freeze_count() > 10_000)")
    assert _run(code)[-1] == "True"


def test_import_leaves_the_collector_and_sys_modules_as_they_were():
    """import ikteach freezes nothing and adds to sys.modules only modules imported the normal
    way: every ikteach module with its own spec, and no module put there by hand without its
    parent package (as a LAPACK table loaded by file path would be)."""
    code = """
import gc, sys
before, frozen = set(sys.modules), gc.get_freeze_count()  # Python 3.12 starts with some frozen
import ikteach
added = set(sys.modules) - before
orphans = [m for m in added if "." in m and m.rsplit(".", 1)[0] not in sys.modules]
ours = [m for m in added if m.startswith("ikteach")]
by_hand = [m for m in ours if sys.modules[m].__spec__ is None or sys.modules[m].__spec__.name != m]
print(gc.get_freeze_count() - frozen, orphans == [] and by_hand == [], "ikteach.core.solve" in added)
"""
    assert _run(code) == ["0", "True", "True"]


def test_setup_without_freezing_leaves_the_collector_alone():
    code = ("import gc; frozen = gc.get_freeze_count(); import ikteach as ik; "
            "ik.notebook.setup(freeze_heap=False); print(gc.get_freeze_count() - frozen)")
    assert _run(code)[-1] == "0"
