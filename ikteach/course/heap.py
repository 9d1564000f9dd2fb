"""A notebook kernel's heap and Python's cycle collector.

After its imports a kernel holds a few hundred thousand objects (the modules, classes and
functions of JAX, matplotlib, IPython and the course) that live as long as it does. Python's
cycle collector walked all of them again in every full collection, 0.1-0.4 s per lecture
notebook, and several times more while the kernel shut down, 0.4-0.7 s per notebook. Frozen
(gc.freeze), they are left out of those walks. Objects made later are collected as before.
"""
import atexit
import gc

_settled = []


def settle():
    """Freeze what is alive now and, at exit, what is left; only on the first call, so that
    running the setup cell again never freezes a notebook's own figures and data (a frozen
    cycle is never freed)."""
    if not _settled:
        gc.freeze()
        _settled.append(atexit.register(gc.freeze))
