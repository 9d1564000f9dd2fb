"""Whole compiled programs kept on disk, so that a new kernel skips tracing and lowering too.

JAX's persistent cache (ik.notebook.compilation_cache) saves XLA's compile, but a new process
still traces and lowers every program to find its cache key: 0.05-0.2 s per solve program,
2-3 s of each of notebooks 06-10 with the cache warm. The store keys a top-level program
(xla.jit: the solve, batch, tracking and clip loops) by what decides it without tracing it:

    the function, the values of its static arguments, the pytree structure, shapes and dtypes
    of the others, and the versions of everything that compiles it (jax, jaxlib, the CPU, the
    compiler options, the source of every ikteach module).

It loads the executable straight back (jax.experimental.serialize_executable). It is on only
where compilation_cache() turned JAX's cache on (the same folder, the same trust: both hold
machine code), and a program falls back to plain jax.jit whenever the key is not certain:

  - a static argument that is not plain data or an ikteach function (a student's step
    function, a closure) has no stable name across processes;
  - an array committed to a device, or a leaf of another kind;
  - any ikteach module whose globals now hold a function from outside the known libraries
    (a module patched from a notebook): a stored program would not see the patch.

A stored program that fails to load or to run is deleted and compiled again with jax.jit.

Two background threads (_background) read ahead, in the order a process last asked for them,
the programs that follow the one just asked for (a notebook run again asks for the same
programs in the same order), and check and write newly compiled programs.
"""
import collections
import contextlib
import dataclasses
import functools
import hashlib
import inspect
import os
import pathlib
import pickle
import platform
import sys
import tempfile
import threading
import time
import types
import warnings

import jax
import numpy as np


FORMAT = "ikteach-program-5"
SUBFOLDER = "programs"
STORE_ENV = "IKTEACH_PROGRAM_STORE"  # "off": JAX's persistent cache only
STALE_DAYS = 14  # env folders (other versions, other source) untouched this long are removed
AHEAD = 4  # programs read ahead in the background: the ones that followed last time

# Modules a function in an ikteach module's globals may come from; anything else (__main__,
# a student's file) means the module was patched and stored programs may not match it.
KNOWN_ROOTS = frozenset({
    "ikteach", "jax", "jaxlib", "numpy", "scipy", "functools", "builtins", "math", "cmath",
    "dataclasses", "typing", "collections", "inspect", "os", "posixpath", "pathlib", "warnings",
    "itertools", "operator", "re", "enum", "abc", "contextlib", "types", "sys", "io", "json",
    "hashlib", "pickle", "platform", "tempfile", "time", "importlib", "textwrap", "string",
    "copy", "weakref", "threading", "subprocess", "shutil", "signal", "struct", "base64",
    "html", "urllib", "zipfile", "gzip", "uuid", "random", "statistics", "numbers", "fractions",
    "decimal", "datetime", "traceback", "logging", "ast", "tokenize", "dis", "linecache",
    "resource", "socket", "select", "selectors", "queue", "multiprocessing", "concurrent",
    "asyncio", "codecs", "unicodedata", "locale", "errno", "stat", "glob", "fnmatch", "csv",
    "matplotlib", "PIL", "skimage", "pyvista", "vtk", "vtkmodules", "ipywidgets", "IPython",
    "nbformat", "nbclient", "jupyter_client", "traitlets", "imageio", "_io", "posix",
    "_operator", "_functools", "_collections", "_thread", "zlib", "bz2", "lzma", "opt_einsum",
    "ml_dtypes", "sre_compile", "sre_parse", "_abc", "_weakref", "_signal", "_sha256",
    "_hashlib", "_pickle", "_json", "_struct", "_random", "_bisect", "bisect", "heapq", "_heapq",
})

# Where a function named in a key may come from: code the environment key versions.
VERSIONED_ROOTS = frozenset({"ikteach", "jax", "jaxlib", "numpy", "builtins", "math",
                             "operator", "functools"})

_root = None  # the folder, once open() was called with a trusted cache
_works = None  # store_works(), once per process
_broken = False  # a stored program misbehaved: plain jax.jit for the rest of the process
_source = None
_lapack_ready = None
_lapack_lock = threading.Lock()
# What the store did this session: programs "loaded" from disk, "compiled" (and written),
# calls left to "plain" jax.jit because the key was not certain.
counts = collections.Counter()
# Read-ahead: "ready" (loaded in the background before it was asked for), "waited" (asked
# for while still loading), "unused" (read ahead, then asked for with other arguments).
ahead_counts = collections.Counter()
_previous = None  # the key of the program this process asked for last
_ahead = {}  # key -> Future of a program read ahead
_asked = set()  # the keys this process asked for (never read ahead again)
_reader = None  # the background threads (reading ahead, checking and writing new programs)
_writing = []  # futures of the files being checked and written


def open_store(cache_dir):
    """Keep programs under cache_dir/programs/<versions>/ (called by compilation_cache).
    Returns that folder, or None (IKTEACH_PROGRAM_STORE=off, or it cannot be created)."""
    global _root
    if os.environ.get(STORE_ENV, "").strip().lower() in ("off", "0", "false", "no"):
        return None
    env = hashlib.sha256(_environment().encode()).hexdigest()[:20]
    base = pathlib.Path(cache_dir) / SUBFOLDER
    try:
        (base / env).mkdir(parents=True, exist_ok=True)
        os.utime(base / env)
        _prune(base, keep=env)
    except OSError:
        return None
    _root = base / env
    return _root


def _prune(base, keep):
    cutoff = time.time() - STALE_DAYS * 86400
    for folder in base.iterdir():
        try:
            if folder.name != keep and folder.is_dir() and folder.stat().st_mtime < cutoff:
                for f in folder.iterdir():
                    f.unlink()
                folder.rmdir()
        except OSError:
            pass


def source_hash():
    """sha256 of every .py file of the ikteach package (any change: new keys)."""
    global _source
    if _source is None:
        package = pathlib.Path(__file__).resolve().parent
        digest = hashlib.sha256()
        for path in sorted(package.rglob("*.py")):
            digest.update(str(path.relative_to(package)).encode() + b"\0" + path.read_bytes())
        _source = digest.hexdigest()
    return _source


def _cpu_flags():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith(("flags", "Features")):
                    return hashlib.sha256(line.encode()).hexdigest()[:16]
    except OSError:
        pass
    return platform.processor()


def _environment():
    import jaxlib

    from . import xla

    device = jax.devices()[0]
    return "\n".join(map(str, [
        FORMAT, sys.version, jax.__version__, getattr(jaxlib, "__version__", "?"),
        jax.default_backend(), device.device_kind, jax.device_count(),
        jax.config.jax_enable_x64, os.environ.get("XLA_FLAGS", ""), sorted((xla.COMPILER_OPTIONS or {}).items()),
        platform.machine(), _cpu_flags(), source_hash()]))


# --- stable descriptions: the same text in every process for the same value, or None -------

def _named(obj):
    """module.qualname for a function or class that is exactly what that name holds now."""
    module, qualname = getattr(obj, "__module__", None), getattr(obj, "__qualname__", None)
    if not isinstance(module, str) or not isinstance(qualname, str) or "<" in qualname:
        return None
    found = sys.modules.get(module)
    for part in qualname.split("."):
        found = getattr(found, part, None)
    return f"{module}.{qualname}" if found is obj else None


def describe(obj, depth=0):
    """A text naming obj's value, equal across processes exactly when the values are; None
    for anything whose value cannot be named that way (then nothing is stored)."""
    if depth > 24:
        return None
    kind = type(obj)
    if obj is None or kind in (bool, int, float, complex, str, bytes):
        return f"{kind.__name__}:{obj!r}"
    if isinstance(obj, np.ndarray):
        data = np.ascontiguousarray(obj)
        if data.dtype == object:
            return None
        return f"ndarray:{data.dtype.str}:{data.shape}:{hashlib.sha256(data.tobytes()).hexdigest()}"
    if isinstance(obj, np.generic):
        return f"{obj.dtype.str}:{obj!r}"
    if isinstance(obj, np.dtype):
        return f"dtype:{obj.str}"
    if isinstance(obj, jax.sharding.Mesh):  # solve_batch's split over the CPU devices
        devices = [(d.platform, d.id) for d in obj.devices.flat]
        return f"mesh:{obj.axis_names!r}:{obj.devices.shape}:{devices}"
    if kind in (tuple, list):
        parts = [describe(x, depth + 1) for x in obj]
        return None if None in parts else f"{kind.__name__}({','.join(parts)})"
    if kind in (set, frozenset):
        parts = [describe(x, depth + 1) for x in obj]
        return None if None in parts else f"{kind.__name__}({','.join(sorted(parts))})"
    if kind is dict:
        items = [(describe(k, depth + 1), describe(v, depth + 1)) for k, v in obj.items()]
        if any(None in item for item in items):
            return None
        return "dict(" + ",".join(sorted(f"{k}:{v}" for k, v in items)) + ")"
    if isinstance(obj, functools.partial):
        parts = [describe(obj.func, depth + 1), describe(obj.args, depth + 1),
                 describe(obj.keywords, depth + 1)]
        return None if None in parts else f"partial({','.join(parts)})"
    if kind is np.ufunc:
        return f"ufunc:{obj.__name__}"
    if isinstance(obj, (types.FunctionType, types.BuiltinFunctionType, type)):
        # only code whose version the key holds: ikteach's source, the libraries' versions
        name = _named(obj)
        if (name is None or name.split(".")[0] not in VERSIONED_ROOTS
                or (isinstance(obj, types.FunctionType) and obj.__closure__)):
            return None
        return f"fn:{name}"
    if dataclasses.is_dataclass(obj) or (isinstance(obj, tuple) and hasattr(kind, "_fields")):
        name = _named(kind)
        if name is None or not name.startswith("ikteach."):
            return None
        values = ([getattr(obj, f.name) for f in dataclasses.fields(obj)]
                  if dataclasses.is_dataclass(obj) else list(obj))
        parts = [describe(v, depth + 1) for v in values]
        return None if None in parts else f"{name}({','.join(parts)})"
    return None


def describe_tree(treedef):
    """The pytree structure, node types and their static data included, or None."""
    data = treedef.node_data()
    if data is None:
        return "*"
    node_type, aux = data
    name, aux_text = describe(node_type), describe(aux)
    if name is None or aux_text is None:
        return None
    children = [describe_tree(c) for c in treedef.children()]
    return None if None in children else f"{name}[{aux_text}]({','.join(children)})"


def _leaf_signature(x):
    """(shape, dtype, weak_type) as jit would see the leaf, or None for a leaf it should see
    for itself (committed arrays, unknown types)."""
    if isinstance(x, jax.Array):
        if x.committed or x.is_deleted():
            return None
        return (x.shape, x.dtype.str, x.weak_type)
    if isinstance(x, np.ndarray):
        return None if x.dtype == object else (x.shape, x.dtype.str, False)
    if isinstance(x, np.generic):
        return ((), x.dtype.str, False)
    if type(x) in (bool, int, float, complex):
        return type(x).__name__
    return None


def patched_modules():
    """ikteach modules whose globals hold functions or classes from unknown modules."""
    found = []
    for name, module in list(sys.modules.items()):
        if module is None or not (name == "ikteach" or name.startswith("ikteach.")):
            continue
        for value in list(vars(module).values()):
            if isinstance(value, functools.partial):
                value = value.func
            if isinstance(value, (types.FunctionType, types.BuiltinFunctionType, type)):
                origin = getattr(value, "__module__", None)
                if not isinstance(origin, str) or origin.split(".")[0] not in KNOWN_ROOTS:
                    found.append(name)
                    break
    return found


class StoredProgram:
    """jax.jit(fun, static_argnames=...) whose executables also live in the store."""

    def __init__(self, fun, jitted, static_argnames=()):
        self._jitted = jitted
        self._signature = inspect.signature(fun)
        params = self._signature.parameters.values()
        self._plain = any(p.kind not in (p.POSITIONAL_OR_KEYWORD, p.POSITIONAL_ONLY)
                          for p in params)  # *args, **kwargs, keyword-only: plain jit
        self._static = frozenset(static_argnames)
        self._loaded = {}
        self._name = f"{fun.__module__}.{fun.__qualname__}"  # the source hash covers its code
        functools.update_wrapper(self, fun)

    def __getattr__(self, name):  # lower, trace, eval_shape, clear_cache, ...
        return getattr(self._jitted, name)

    def __call__(self, *args, **kwargs):
        if _root is None or _broken or self._plain:
            return self._jitted(*args, **kwargs)
        return self._call(args, kwargs)

    def _call(self, args, kwargs):
        try:
            bound = self._signature.bind(*args, **kwargs)
        except TypeError:
            return self._jitted(*args, **kwargs)  # jit says what is wrong
        bound.apply_defaults()
        values = bound.arguments
        static = tuple((k, v) for k, v in values.items() if k in self._static)
        dynamic = tuple(v for k, v in values.items() if k not in self._static)
        leaves, treedef = jax.tree_util.tree_flatten(dynamic)
        if any(isinstance(leaf, jax.core.Tracer) for leaf in leaves):
            return self._jitted(*args, **kwargs)  # called while tracing another program
        signature = tuple(map(_leaf_signature, leaves))
        if None in signature:
            counts["plain"] += 1
            return self._jitted(*args, **kwargs)
        try:
            memory_key = (static, treedef, signature)
            program = self._loaded.get(memory_key)
        except TypeError:  # an unhashable static value: jit reports it
            return self._jitted(*args, **kwargs)
        if program is None:
            program, out = self._program(memory_key, tuple(values.values()), static, dynamic,
                                         treedef, signature)
            if program is None:
                counts["plain"] += 1
                return self._jitted(*args, **kwargs)
            if out is not None:
                return out  # the first run, made while checking the stored copy
        try:
            # errors of execution surface when the result is read: read it here, so that a
            # stored program that cannot run is dropped rather than failing the caller
            return jax.block_until_ready(program(*dynamic))
        except Exception:
            _give_up(self._loaded.pop(memory_key, None))
            return self._jitted(*args, **kwargs)

    def _program(self, memory_key, positional, static, dynamic, treedef, signature):
        """(program, output of its first run or None); (None, None): use plain jit."""
        if patched_modules():
            return None, None
        described = [describe(static), describe_tree(treedef), self._name]
        if None in described:
            return None, None
        key = hashlib.sha256("\n".join(described + [repr(signature)]).encode()).hexdigest()
        path = _root / f"{key}.bin"
        in_tree = jax.tree_util.tree_structure((dynamic, {}))
        program, out = _read_ahead_or_load(key, path, in_tree), None
        _follow(key)
        if program is not None:
            counts["loaded"] += 1
        else:
            program, out = _compile_and_save(self._jitted, positional, dynamic, in_tree, path)
            if program is not None:
                counts["compiled"] += 1
        if program is not None:
            self._loaded[memory_key] = program
        return program, out


class _Loaded:
    """A Compiled with the file it came from (deleted should it fail) and its input tree."""

    def __init__(self, compiled, store_path, in_tree):
        self.compiled, self.store_path, self.in_tree = compiled, store_path, in_tree

    def __call__(self, *args):
        return self.compiled(*args)


def lapack_ready():
    """Point jaxlib's LAPACK kernels at their library. Lowering a linear solve does this; a
    program loaded without lowering anything would call through null pointers (a crash), so
    jax.export does it before loading too. False where this jaxlib has no such call."""
    global _lapack_ready
    with _lapack_lock:  # the background threads ask too
        if _lapack_ready is None:
            _lapack_ready = _initialize_lapack()
    return _lapack_ready


def _initialize_lapack():
    try:
        from jax._src.lax import linalg

        linalg.initialize_lapack()
        return True
    except Exception:
        try:
            from jaxlib.cpu import _lapack

            _lapack.initialize()
            return True
        except Exception:
            return False


def _load(path, in_tree=None):
    """The program in a store file, for arguments of structure in_tree (None: the file's)."""
    from jax.experimental import serialize_executable

    try:
        blob = path.read_bytes()
    except OSError:
        return None
    try:
        serialized, file_tree, out_tree, device_ids, needs_lapack = pickle.loads(blob)
        if in_tree is not None and in_tree != file_tree:
            raise ValueError("another program's file")
        if needs_lapack and not lapack_ready():
            return None
        by_id = {d.id: d for d in jax.devices()}
        compiled = serialize_executable.deserialize_and_load(
            serialized, file_tree, out_tree, execution_devices=[by_id[i] for i in device_ids])
        return _Loaded(compiled, path, file_tree)
    except Exception:  # a truncated or foreign file: compile again
        _unlink(path)
        return None


def _read_ahead_or_load(key, path, in_tree):
    """The program, from the background reader if it was read ahead, else from its file."""
    future = _ahead.pop(key, None)
    if future is not None:
        ahead_counts["ready" if future.done() else "waited"] += 1
        try:
            program = future.result()
        except Exception:
            program = None
        if program is not None and program.in_tree == in_tree:
            return program
        ahead_counts["unused"] += 1
    return _load(path, in_tree)


def _follow(key):
    """Note that key came after the previous program asked for (in <previous>.next), then
    read ahead, in background threads, the programs that followed key last time: a notebook
    run again asks for the same programs in the same order, and loading one (20-80 ms, most
    of it outside Python's lock) then overlaps the cells before it is needed."""
    global _previous
    previous, _previous = _previous, key
    _asked.add(key)
    try:
        if previous is not None and previous != key:
            marker = _root / f"{previous}.next"
            if not marker.exists() or marker.read_text() != key:
                _write(marker, key.encode())
        following = key
        for _ in range(AHEAD):
            marker = _root / f"{following}.next"
            if _broken or not marker.exists():
                break
            following = marker.read_text().strip()
            if following in _asked or following in _ahead or not following.isalnum():
                continue  # already here, already loading, or not a key
            _ahead[following] = _background().submit(_load, _root / f"{following}.bin")
    except OSError:
        pass


def _background():
    global _reader
    if _reader is None:
        import concurrent.futures

        _reader = concurrent.futures.ThreadPoolExecutor(2, thread_name_prefix="ikteach-store")  # 2 cores
    return _reader


def _compile_and_save(jitted, positional, dynamic, in_tree, path):
    """Compile (without JAX's persistent cache), run, and have a background thread write
    the store's file, only once a copy read back from its bytes gives the same output to the
    bit. An executable that JAX took from its own cache, or from this process's memory of one
    (a plain jit call of the same program), serializes into bytes that load but do not run
    ("Function ... not found"): the check keeps those out. Serialized, checked and written
    in the background, it costs the caller nothing (a cold notebook compiles 20-30 programs).
    Returns (the compiled program, its output), or (None, None) to leave it to jax.jit."""
    if not store_works():
        return None, None  # plain jit, through JAX's cache
    try:
        with _without_jax_cache():
            compiled = jitted.lower(*positional).compile()
        out = jax.block_until_ready(compiled(*dynamic))
    except Exception:
        return None, None  # jit raises it again, with its own message
    try:
        inputs = jax.tree_util.tree_map(_frozen, dynamic)  # the caller may change its arrays
        _writing[:] = [f for f in _writing if not f.done()]
        _writing.append(_background().submit(_check_and_write, compiled, in_tree, inputs, out, path))
    except Exception:
        pass  # no thread to write it: run it all the same
    return _Loaded(compiled, path, in_tree), out


def _frozen(leaf):
    return np.array(leaf) if isinstance(leaf, np.ndarray) else leaf


def _check_and_write(compiled, in_tree, args, out, path):
    try:
        parts = _serialized(compiled)
        blob = None if parts is None else _checked_bytes(parts, in_tree, args, out)
        if blob is not None:
            _write(path, blob)
    except Exception:
        pass  # not serializable here, the copy failed or the folder is read-only: no file


def finish_writing():
    """Wait until the background threads have written every program compiled so far."""
    while _writing:
        _writing.pop().result()


def _serialized(compiled):
    """(bytes, out_tree, devices in order, calls LAPACK) for a compiled program; None where its
    LAPACK calls cannot be set up here."""
    from jax.experimental import serialize_executable

    needs_lapack = calls_lapack(compiled)
    if needs_lapack and not lapack_ready():
        return None
    serialized, _, out_tree = serialize_executable.serialize(compiled)
    devices = list(compiled._executable.xla_executable.local_devices())  # in its order
    return serialized, out_tree, devices, needs_lapack


def _checked_bytes(parts, in_tree, args, out):
    """The store's file for a serialized program that gave `out` on `args`, or None when a
    copy read back from its bytes does not give the same output to the bit."""
    from jax.experimental import serialize_executable

    serialized, out_tree, devices, needs_lapack = parts
    copy = serialize_executable.deserialize_and_load(serialized, in_tree, out_tree,
                                                     execution_devices=devices)
    if not same_bits(out, jax.block_until_ready(copy(*args))):
        return None
    return pickle.dumps((serialized, in_tree, out_tree, [d.id for d in devices], needs_lapack),
                        protocol=pickle.HIGHEST_PROTOCOL)


@contextlib.contextmanager
def _without_jax_cache():
    """JAX decides once per process whether its persistent cache is in use (the setting
    alone cannot turn it off later): answer "no" to that question while compiling. Where
    this JAX has no such function the compile may come from its cache, and the check in
    _checked_bytes then keeps the bytes off disk."""
    try:
        from jax._src import compilation_cache
        used = compilation_cache.is_cache_used
    except (ImportError, AttributeError):
        yield
        return
    compilation_cache.is_cache_used = lambda backend: False
    try:
        yield
    finally:
        compilation_cache.is_cache_used = used


def _round_trip(fun, *args):
    """Compile fun (past JAX's cache), write, read back and run it: the same bits?"""
    with _without_jax_cache():
        compiled = jax.jit(fun).lower(*args).compile()
    out = jax.block_until_ready(compiled(*args))
    parts = _serialized(compiled)
    return parts is not None and _checked_bytes(parts, jax.tree_util.tree_structure((args, {})),
                                                args, out) is not None


def store_works():
    """Once per process, before the first program is compiled for the store: can this JAX
    write a program and read it back (a one-line program, about 30 ms)? If not, programs
    stay with jax.jit and JAX's own cache, which the store's compiles bypass."""
    global _works
    if _works is None:
        try:
            _works = _round_trip(lambda x, n: (x * n).sum(), np.arange(3.0), 2)
        except Exception:
            _works = False
    return _works


def calls_lapack(compiled):
    """Does the program call jaxlib's LAPACK kernels (SVD, solves)? Those need lapack_ready()
    before it runs (scipy's tables were loaded at import, see lapack_tables): loads of other
    programs skip it."""
    try:
        return 'custom_call_target="lapack_' in compiled.as_text()
    except Exception:
        return True


def same_bits(a, b):
    """Two pytrees of arrays with the same structure, shapes, dtypes and bytes."""
    leaves_a, tree_a = jax.tree_util.tree_flatten(a)
    leaves_b, tree_b = jax.tree_util.tree_flatten(b)
    if tree_a != tree_b:
        return False
    for x, y in zip(leaves_a, leaves_b):
        x, y = np.asarray(x), np.asarray(y)
        if x.dtype != y.dtype or x.shape != y.shape or x.tobytes() != y.tobytes():
            return False
    return True


def _write(path, blob):
    """Write whole or not at all (another kernel may be reading or writing the same file)."""
    with tempfile.NamedTemporaryFile(dir=path.parent, delete=False, suffix=".tmp") as f:
        temporary = pathlib.Path(f.name)
        try:
            f.write(blob)
        except OSError:
            f.close()
            _unlink(temporary)
            raise
    os.replace(temporary, path)


def _unlink(path):
    try:
        path.unlink()
    except OSError:
        pass


def _give_up(program):
    """A stored program failed: remove its file and use plain jax.jit from now on."""
    global _broken
    if program is not None:
        _unlink(program.store_path)
    if not _broken:
        _broken = True
        warnings.warn("ikteach: a compiled program from the store failed to run; compiling "
                      "with jax.jit for the rest of this session", RuntimeWarning, stacklevel=3)

