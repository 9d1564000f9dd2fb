"""The student's functions stay in the notebook's job (cells.py: the cells ran there, in IPython's
shell); the checks call them through proxies and compute the marks in the grader's own process.

After the cells the job answers calls: one JSON line per request and per reply on its own pipes
(its stdout and stdin are /dev/null to the student's code). Values cross as JSON (numbers,
strings, lists, dicts, arrays as nested lists); a function the student returns (a step function)
stays in the job and crosses as a handle; a function of ikteach that the checks pass crosses by
its name. Whatever the job sends can only be a value of the student's own function: the verdict
is computed here, by the checks of this process's ikteach. Everything a job says is bounded
here (MAX_REPLY, MAX_NOTES, MAX_NAMES, MAX_HELD), however many notebooks a student hands in."""
import functools
import importlib
import json
import os
import select
import time
import traceback

from .time_limit import CELLS_BUSY

STARTUP_LIMIT = 120.0    # seconds for the job to start (the fork server's fork: milliseconds)
CALL_LIMIT = 600.0       # last-resort limit on one reply (the checks' own limit is shorter)
MAX_REPLY = 64 << 20     # bytes
MAX_NOTES, MAX_NAMES, MAX_HELD = 30, 200, 200
GRACE = 15.0             # seconds past the cells' own alarm before the job is killed
HELD_LIMIT = 5.0         # seconds for the fingerprints of the code a notebook's source defines


class ProcessEnded(Exception):
    """The worker running the student's code ended (os._exit, a crash, a resource limit)."""


class _Opaque:
    """A value that cannot cross as JSON; keeps its type name and repr for the message."""

    def __init__(self, text):
        self.text = text

    def __repr__(self):
        return self.text


# --- values across the pipe ---------------------------------------------------------------------

def encode(value, handles=None):
    """A JSON-able form of value; callables become handles (worker) or names (grader)."""
    import numpy as np

    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return value
    if isinstance(value, (list, tuple)):
        return {"__list__" if isinstance(value, list) else "__tuple__":
                [encode(v, handles) for v in value]}
    if isinstance(value, dict):
        return {"__dict__": [[encode(k, handles), encode(v, handles)] for k, v in value.items()]}
    if isinstance(value, functools.partial):
        return {"__ref__": _name_of(value.func), "args": encode(value.args, handles),
                "kwargs": encode(value.keywords, handles)}
    if hasattr(value, "__array__") or isinstance(value, np.generic):
        arr = np.asarray(value)
        if arr.dtype.kind in "biuf":
            return {"__nd__": arr.tolist(), "dtype": arr.dtype.str}
    if callable(value):
        if handles is None:  # the grader's side: only ikteach's own functions cross
            return {"__ref__": _name_of(value), "args": None, "kwargs": None}
        handles.append(value)
        return {"__handle__": len(handles) - 1}
    return {"__opaque__": type(value).__name__[:60], "repr": repr(value)[:80]}


def _name_of(fn):
    module, name = getattr(fn, "__module__", "") or "", getattr(fn, "__qualname__", "")
    if not module.startswith("ikteach") or "<" in name:
        raise TypeError(f"only ikteach's module-level functions can be passed, got {fn!r}")
    return f"{module}:{name}"


def decode(data, call=None):
    """The value from its JSON form; `call(handle, args)` makes handles callable (grader)."""
    import numpy as np

    if not isinstance(data, dict):
        return data
    if "__list__" in data:
        return [decode(v, call) for v in data["__list__"]]
    if "__tuple__" in data:
        return tuple(decode(v, call) for v in data["__tuple__"])
    if "__dict__" in data:
        out = {}
        for k, v in data["__dict__"]:
            key = decode(k, call)
            out[key if isinstance(key, (str, int, float, bool, type(None), tuple)) else str(key)] \
                = decode(v, call)
        return out
    if "__nd__" in data:  # numbers only: a dtype such as V1000000000 would fill the memory
        dtype = np.dtype(str(data["dtype"]))
        if dtype.kind not in "biuf" or dtype.itemsize > 16:
            raise ValueError(f"not an array of numbers: {dtype}")
        return np.array(data["__nd__"], dtype=dtype)
    if "__handle__" in data and call is not None:
        handle = int(data["__handle__"])
        return functools.wraps(_handle_doc)(lambda *args: call(handle, args))
    if "__ref__" in data and call is None:  # the worker's side: ikteach's function by name
        module, name = str(data["__ref__"]).split(":")
        if not module.startswith("ikteach"):
            raise ValueError(f"not an ikteach function: {module}")
        fn = functools.reduce(getattr, name.split("."), importlib.import_module(module))
        if data.get("args") is None and data.get("kwargs") is None:
            return fn
        return functools.partial(fn, *decode(data["args"]), **decode(data["kwargs"]))
    if "__opaque__" in data:
        kind = type(str(data["__opaque__"])[:60] or "object", (_Opaque,), {})
        return kind(str(data.get("repr", ""))[:80])
    return {}


def _handle_doc(*args):
    """A function your code returned (it runs in your code's process)."""


# --- the job's side -------------------------------------------------------------------------------

def _student_line(exc):
    for frame in reversed(traceback.extract_tb(exc.__traceback__)):
        if frame.filename.startswith("<cell "):
            code = f": {frame.line.strip()}" if frame.line else ""
            return f" ({frame.filename[1:-1]}, line {frame.lineno}{code})"
    return ""


def serve(namespace, graded, requests, send):
    """After the cells (cells.py): say what the namespace holds, then answer calls, one JSON
    line each, until the grader closes the requests."""
    from ikteach.core.solve import StopSolve
    from ikteach.course.grading import own_code

    callables = sorted(k for k, v in namespace.items() if callable(v) and k[:2] != "__")
    first = [k for k in graded if k in callables]  # the grader keeps MAX_NAMES: graded ones first
    send({"ready": first + [k for k in callables if k not in first],
          "foreign": own_code.foreign(namespace, graded)})
    handles = []
    for line in requests:
        request = json.loads(line)
        try:
            if "handle" in request:
                fn = handles[int(request["handle"])]
            else:
                fn = namespace[str(request["name"])]
            args = decode(request["args"])
            send({"value": encode(fn(*args), handles)})
        except StopSolve as exc:
            send({"raise": {"kind": "stop", "message": str(exc)[:200]}})
        except NotImplementedError:
            send({"raise": {"kind": "not yet"}})
        except BaseException as exc:  # noqa: B036 - the student's error, reported
            text = str(exc).splitlines()[0][:300] if str(exc) else ""
            send({"raise": {"kind": "error", "type": type(exc).__name__[:80], "message": text,
                            "line": _student_line(exc)}})


# --- the grader's side ------------------------------------------------------------------------------

def _used(message, timeout):
    """Why the cells' time limit stopped them (the job's "used": [CPU s, wall s])."""
    try:
        cpu, wall = (float(v) for v in message["used"])
    except (KeyError, TypeError, ValueError):  # forged
        cpu, wall = timeout, 0.0
    held = f" in {wall:.0f} s: this machine is busy (or the notebook waits)"
    return f"stopped after {cpu:.1f} s of CPU time{held if cpu < timeout else ''}"


class Worker:
    """One notebook's job: a fresh child of the sandbox's fork server for `exercise`
    (servers.py: its copy of ikteach has no answer to it), started by start(): its `cells` run
    (at most `timeout` s in all), then it serves the checks' calls. graded: the names the check
    grades; `limit`: seconds for the checks (every call), applied from outside the student's
    process: it is then killed, whatever it does with its signals. After start(): errors
    (cells that raised), notes (what went wrong on the way), names, foreign (graded names not
    written in the notebook)."""

    def __init__(self, cells, sandbox, exercise=None, graded=(), limit=CALL_LIMIT,
                 timeout=STARTUP_LIMIT):
        self.cells, self.sandbox, self.exercise = cells, sandbox, exercise
        self.graded = list(graded)
        self.setup = {"cells": cells, "graded": self.graded, "timeout": float(timeout)}
        self.limit, self.timeout, self.deadline = limit, timeout, None
        self.process, self.names, self.errors, self.notes = None, [], [], []
        self.foreign, self._buffer = {}, b""
        self.stopped, self._cpu = False, 0.0  # stopped: a call the checks' time limit ended

    def start(self):
        """Run the cells; raises ProcessEnded when the job did not get to its checks (the notes
        then say which cell it was in)."""
        from .servers import server_for

        # past the job's own alarm (its cells' limit): killed from outside (`grace`: start-up too)
        grace, held_up = min(GRACE, self.timeout) + GRACE, CELLS_BUSY * self.timeout
        server = server_for(self.sandbox, self.exercise)  # a server's start is not the job's
        self.deadline = time.monotonic() + held_up + grace
        self.process = server.job("notebook", held_up + grace + self.limit, self.setup)
        self.cells_cpu = self.cpu_seconds() + self.timeout + grace
        cell = None
        try:
            while True:
                try:
                    message = self._read(self.deadline - time.monotonic(), during="cells")
                except ProcessEnded as exc:
                    where = "before its first cell" if cell is None else f"in cell {cell}"
                    self.notes.append(f"the notebook's run ended {where}: {exc}")
                    raise
                if not isinstance(message, dict):
                    continue
                if "ready" in message:
                    break
                full = len(self.errors) + len(self.notes) >= MAX_NOTES  # bounded on arrival
                if "error" in message and not full:
                    self.errors.append(str(message["error"])[:400])
                if "stopped" in message and not full:
                    why = _used(message, self.timeout)
                    self.notes.append(f"cell {str(message['stopped'])[:20]} did not finish "
                                      f"within the notebook's time limit: {why}")
                cell = str(message["cell"])[:20] if "cell" in message else cell
        except BaseException:
            self.end()
            raise
        self.deadline = time.monotonic() + self.limit
        self.names = [str(n)[:200] for n in message.get("ready", [])][:MAX_NAMES]
        foreign = message.get("foreign", {})
        self.foreign = {k: str(v)[:400] for k, v in foreign.items()
                        if k in self.graded} if isinstance(foreign, dict) else {}
        return self

    def _write(self, message):
        self.process.write((json.dumps(message) + "\n").encode())

    def _read(self, timeout, during="checks"):
        """The job's next message (one JSON line), waiting at most `timeout` s and never past
        the deadline (of the cells or of the checks: `during`)."""
        fd = self.process.fileno()
        while b"\n" not in self._buffer or self.deadline < time.monotonic():
            left, cells = self.deadline - time.monotonic(), during == "cells"
            wait = min(max(timeout, 0.0), left, 1.0 if cells else left)
            ready = left > 0 and select.select([fd], [], [], wait)[0]
            if not ready and cells:  # the cells' CPU limit read from outside too, each second
                if left > 0 and self.cpu_seconds() < self.cells_cpu:
                    continue
                raise ProcessEnded("it did not finish within the notebook's time limit "
                                   f"({self.timeout:g} s of CPU time) and ignored the "
                                   "alarm: it was killed, and nothing could be graded")
            if not ready and left <= timeout:
                raise ProcessEnded(f"your code ran past the grading time limit of "
                                   f"{self.limit:g} s: it was stopped")
            if not ready:
                raise ProcessEnded(f"no answer within {timeout:g} s")
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                code = self.process.end(wait_for_exit=5)["status"]
                raise ProcessEnded(f"the process running your code ended (exit status {code}:"
                                   " os._exit, a crash, or a CPU/memory limit)")
            self._buffer += chunk
            if len(self._buffer) > MAX_REPLY:
                raise ProcessEnded("your function's result is too large to check")
        line, _, self._buffer = self._buffer.partition(b"\n")
        return json.loads(line)

    def call(self, target, args):
        """target: a name (str) or a handle (int); returns the value or raises as the student's
        function did (NotImplementedError, ik.StopSolve, or an error with its student_line)."""
        from ...core.solve import StopSolve

        if self.process is None:
            raise ProcessEnded("the process running your code was ended earlier")
        request = {"handle" if isinstance(target, int) else "name": target,
                   "args": encode(list(args))}  # before the try: a value that cannot cross
        try:                                    # (a JAX tracer) leaves the worker running
            self._write(request)
            reply = self._read(CALL_LIMIT)
        except BaseException as exc:  # a time limit, or a broken worker: end it, it may be busy
            self.stopped = self.stopped or not isinstance(exc, Exception)
            self.end()
            raise
        if not isinstance(reply, dict):
            self.end()
            raise ProcessEnded("the process running your code answered garbage")
        if "value" in reply:
            return decode(reply["value"], call=self.call)
        raised = reply.get("raise") if isinstance(reply.get("raise"), dict) else {}
        if raised.get("kind") == "stop":
            raise StopSolve(str(raised.get("message", ""))[:200])
        if raised.get("kind") == "not yet":
            raise NotImplementedError
        error = type(str(raised.get("type", "Error"))[:80] or "Error", (Exception,), {})(
            str(raised.get("message", ""))[:300])
        error.student_line = str(raised.get("line", ""))[:300]
        raise error

    def held(self):
        """{fingerprint: function name} of the code the cells' source defines, computed in a job
        of its own, where no student code has run (the notebook's own job could forge it); {}
        where that job fails. Call it before start(): a fork server runs one job at a time."""
        from .servers import server_for

        job = server_for(self.sandbox, self.exercise).job(
            "fingerprints", HELD_LIMIT + GRACE, {"cells": self.cells})
        found, data, deadline = {}, b"", time.monotonic() + HELD_LIMIT + GRACE
        try:
            while not data.endswith(b"\n") and len(data) < MAX_REPLY:
                left = max(0.0, deadline - time.monotonic())
                if not select.select([job.fileno()], [], [], left)[0]:
                    break
                chunk = os.read(job.fileno(), 1 << 20)
                if not chunk:
                    break
                data += chunk
            found = json.loads(data) if data.endswith(b"\n") else {}
        except ValueError:
            pass
        finally:
            job.end()
        return {str(k)[:64]: str(v)[:80] for k, v in list(found.items())[:MAX_HELD]} \
            if isinstance(found, dict) else {}

    def cpu_seconds(self):
        """CPU seconds the job's sandbox has used so far (what the checks' limits count)."""
        if self.process is not None:
            self._cpu = self.process.server.process.cpu_seconds()
        return self._cpu

    def function(self, name):
        return functools.wraps(_handle_doc)(lambda *args: self.call(name, args))

    def end(self):
        if self.process is not None:
            self.process.end()
            self.process = None

