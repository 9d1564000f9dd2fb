"""Whether the grader's sandbox works on this machine (checked once per test process)."""
from ikteach.course.grading.sandbox import Sandbox, SandboxUnavailable


def _have_sandbox():
    try:
        Sandbox().close()
        return True
    except SandboxUnavailable:
        return False


SANDBOXED = _have_sandbox()
