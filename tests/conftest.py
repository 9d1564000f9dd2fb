import os

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

from hypothesis import settings  # noqa: E402

settings.register_profile("ikteach", max_examples=25, deadline=None)
settings.load_profile("ikteach")

# Wrong and hostile submissions for tests/test_grade.py: graded there, never run by nbval.
collect_ignore_glob = ["submissions/*"]

# Compiled programs are kept on disk between runs, as in the notebooks (ik.notebook.setup):
# a second `make test` loads them instead of compiling (IKTEACH_JAX_CACHE=off turns it off).
from ikteach.notebook import compilation_cache  # noqa: E402

compilation_cache()
