import os

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

from hypothesis import settings  # noqa: E402

settings.register_profile("ikteach", max_examples=25, deadline=None)
settings.load_profile("ikteach")

# Wrong and hostile submissions for tests/test_grade.py: graded there, never run by nbval.
collect_ignore_glob = ["submissions/*"]
