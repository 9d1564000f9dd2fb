import os

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

from hypothesis import settings  # noqa: E402

settings.register_profile("ikteach", max_examples=25, deadline=None)
settings.load_profile("ikteach")


def pytest_configure(config):
    # a plugin, not this file's hooks: those reach only the items under tests/
    from lecture_budgets import LectureBudgets

    config.pluginmanager.register(LectureBudgets(), "ikteach-lecture-budgets")
    config.addinivalue_line("markers", "without_bwrap: its outcome depends on whether bubblewrap "
                            "works (.ci/run runs them again with bwrap hidden from PATH)")


# Wrong and hostile submissions for tests/test_grade.py: graded there, never run by nbval.
collect_ignore_glob = ["submissions/*"]

# Compiled programs are kept on disk between runs, as in the notebooks (ik.notebook.setup):
# a second `make test` loads them instead of compiling (IKTEACH_JAX_CACHE=off turns it off).
from ikteach.course.notebook import compilation_cache  # noqa: E402

compilation_cache()


def _retry_nbval_kernel_start(attempts=3):
    """nbval starts one kernel per notebook; with two xdist workers starting kernels at once,
    about one start in a hundred dies before answering kernel_info (a port taken between
    jupyter_client choosing it and the kernel binding it). jupyter_client shuts a failed start
    down, so start again: a start that fails every time still fails the notebook."""
    try:
        from nbval import kernel
    except ImportError:
        return
    start = kernel.RunningKernel.__init__

    def init(self, *args, **kwargs):
        for attempt in range(attempts):
            try:
                return start(self, *args, **kwargs)
            except RuntimeError:
                if attempt == attempts - 1:
                    raise

    kernel.RunningKernel.__init__ = init


_retry_nbval_kernel_start()
