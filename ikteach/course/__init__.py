"""The course's own tooling: notebook setup, header and strip, the course home, exercise
checks (check/), the exercise builder, grading and its sandbox (grading/)."""
from .._lazy import submodules  # noqa: E402

__getattr__ = submodules(__name__, globals())  # ik.course.<module>: imported on first use
