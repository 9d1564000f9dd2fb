"""ikteach.program_store: a program loaded whole from disk computes exactly what jax.jit does,
and the store steps aside wherever its key could be wrong."""
import json
import math
import os
import subprocess
import sys
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ikteach as ik
from ikteach import program_store, xla

# Each kind of stored program once: solve (no LAPACK; a pose target's DLS solves with LAPACK;
# FABRIK's loops), solve_batch on one device and split over several (a mesh), and track. Floats as hex: equal means equal to the last bit.
SCRIPT = """
import json, numpy as np, ikteach as ik
from ikteach import program_store
ik.notebook.compilation_cache()
planar, ur5 = ik.planar_chain([1.0, 0.7, 0.4]), ik.ur5()
pose = np.asarray(ik.fk_pose(ur5, np.full(6, 0.4)))
hexes = lambda x: [float(v).hex() for v in np.ravel(x)]
out = {}
for name, (arm, target, method) in {"jt": (planar, [1.2, 0.9], "jt"),
                                    "fabrik": (planar, [1.2, 0.9], "fabrik"),
                                    "dls pose": (ur5, pose, "dls")}.items():
    r = ik.solve(arm, target, np.full(arm.n_joints, 0.2), method=method, max_iter=200)
    out[name] = [r.status, r.iterations, hexes(r.theta), hexes(r.trace.error)]
for side in (12, 33):  # 1089 targets: split over the CPU devices where there are two or more
    g = np.linspace(-2.3, 2.3, side)
    b = ik.solve_batch(planar, np.stack(np.meshgrid(g, g), -1).reshape(-1, 2), [0.3, 0.2, 0.1])
    out[f"batch {side}"] = [b.status.tolist(), b.iterations.tolist(), hexes(b.theta)]
t = ik.track(planar, np.linspace([1.5, 0.2], [0.3, 1.4], 30), [0.3, 0.2, 0.1])
out["track"] = hexes(t.theta)
out["counts"] = dict(program_store.counts)
out["ahead"] = dict(program_store.ahead_counts)
import sys
out["scipy.linalg"] = "scipy.linalg" in sys.modules  # a load needs only its LAPACK tables
import scipy.linalg  # and scipy.linalg imports as usual after them
assert np.allclose(scipy.linalg.solve(np.diag([2.0, 4.0]), [1.0, 1.0]), [0.5, 0.25])
print(json.dumps(out))
"""


def run_script(cache, store="on"):
    env = dict(os.environ, IKTEACH_JAX_CACHE=str(cache), IKTEACH_PROGRAM_STORE=store)
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                          env=env, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    out = json.loads(done.stdout.splitlines()[-1])
    out["counts"]["scipy.linalg imported"] = out.pop("scipy.linalg")
    out["counts"]["read ahead"] = out.pop("ahead")
    return out.pop("counts"), out


def test_a_second_process_loads_every_program_and_gets_the_same_bits(tmp_path):
    """The first process compiles as jax.jit does (the same lowering, compiled); the second
    loads every program from disk, traces nothing, and gets the same bits."""
    first_counts, first = run_script(tmp_path)
    second_counts, second = run_script(tmp_path)
    assert first_counts.get("compiled", 0) >= 6 and first_counts.get("loaded", 0) == 0
    assert not first_counts["scipy.linalg imported"]  # see test_lapack_tables
    assert first_counts["read ahead"] == {}  # nothing to go on yet
    ahead = second_counts.pop("read ahead")
    assert second_counts == {"loaded": first_counts["compiled"],  # no tracing, no compiling
                             "scipy.linalg imported": False}
    # every program after the first was read ahead, in the order the first process used them
    assert ahead.get("ready", 0) + ahead.get("waited", 0) == first_counts["compiled"] - 1
    assert "unused" not in ahead
    assert second == first
    assert first["dls pose"][0] == "converged" and first["jt"][0] == "converged"


def test_the_store_can_be_turned_off(tmp_path, monkeypatch):
    monkeypatch.setattr(program_store, "_root", None)
    monkeypatch.setenv(program_store.STORE_ENV, "off")
    assert program_store.open_store(tmp_path) is None and program_store._root is None


MEMO_SCRIPT = """
import sys, numpy as np, ikteach as ik
from ikteach import program_store
ik.notebook.compilation_cache()
arm = ik.planar_chain([1.0, 0.7, 0.4])
if sys.argv[1] == "plain first":  # jax.jit runs it first (from JAX's cache), then the store
    root, program_store._root = program_store._root, None
    ik.solve(arm, [1.2, 0.9], np.full(3, 0.2), method="jt")
    program_store._root = root
r = ik.solve(arm, [1.2, 0.9], np.full(3, 0.2), method="jt")
print(r.status, r.iterations, float(r.error).hex(), "+".join(sorted(program_store.counts)))
"""


def test_an_executable_from_jaxs_cache_is_never_stored(tmp_path):
    """JAX hands back an executable it loaded from its own cache (here: from its memory of
    the plain jit call) and that one serializes into bytes that load but cannot run. The
    store checks a copy read back from the bytes before writing them."""
    def run(*args, store="on"):
        env = dict(os.environ, IKTEACH_JAX_CACHE=str(tmp_path), IKTEACH_PROGRAM_STORE=store)
        done = subprocess.run([sys.executable, "-c", MEMO_SCRIPT, *args], capture_output=True,
                              text=True, env=env, timeout=300)
        assert done.returncode == 0 and "Warning" not in done.stderr, done.stderr[-3000:]
        return done.stdout.split()

    plain = run("", store="off")  # fills JAX's cache
    first = run("plain first")
    assert first[-1] == "compiled"  # compiled, checked, not written
    assert list(tmp_path.glob("programs/*/*.bin")) == []
    second = run("")
    assert second[:3] == first[:3] == plain[:3]
    assert second[-1] == "compiled" and len(list(tmp_path.glob("programs/*/*.bin"))) == 1
    assert run("") == second[:3] + ["loaded"]


def test_same_bits_tells_any_difference():
    a = {"x": np.arange(3.0), "n": np.int64(2)}
    assert program_store.same_bits(a, {"x": np.arange(3.0), "n": np.int64(2)})
    assert not program_store.same_bits(a, {"x": np.array([0.0, 1.0, np.nextafter(2.0, 3.0)]), "n": np.int64(2)})
    assert not program_store.same_bits(a, {"x": np.arange(3), "n": np.int64(2)})
    assert not program_store.same_bits(a, {"x": np.arange(3.0), "m": np.int64(2)})
    assert program_store.same_bits(np.array([np.nan]), np.array([np.nan]))


@pytest.fixture
def store(tmp_path, monkeypatch):
    """A fresh store for this test only."""
    monkeypatch.setattr(program_store, "_root", None)
    monkeypatch.setattr(program_store, "_broken", False)
    monkeypatch.setattr(program_store, "counts", program_store.collections.Counter())
    monkeypatch.setattr(program_store, "ahead_counts", program_store.collections.Counter())
    monkeypatch.setattr(program_store, "_previous", None)
    monkeypatch.setattr(program_store, "_ahead", {})
    monkeypatch.setattr(program_store, "_asked", set())
    monkeypatch.setattr(program_store, "_writing", [])
    assert program_store.open_store(tmp_path) is not None
    return program_store


def square_sum(x, scale, power):
    return scale * jnp.sum(x ** power)


def test_programs_are_kept_by_shape_and_static_value(store):
    program = xla.jit(square_sum, static_argnames=("power",))
    assert float(program(jnp.arange(3.0), 2.0, power=2)) == 10.0
    assert float(program(jnp.arange(3.0), 3.0, power=2)) == 15.0  # new value: same program
    assert float(program(jnp.arange(4.0), 1.0, power=2)) == 14.0  # new shape
    assert float(program(jnp.arange(3.0), 1.0, power=3)) == 9.0  # new static value
    assert store.counts == {"compiled": 3}
    store.finish_writing()  # files are checked and written in the background
    assert len(list(store._root.glob("*.bin"))) == 3
    program._loaded.clear()  # as in a new process
    assert float(program(jnp.arange(3.0), 1.0, power=3)) == 9.0
    assert store.counts["loaded"] == 1


def test_a_damaged_file_is_compiled_again(store):
    program = xla.jit(square_sum, static_argnames=("power",))
    program(jnp.arange(3.0), 2.0, power=2)
    store.finish_writing()  # files are checked and written in the background
    (path,) = store._root.glob("*.bin")
    path.write_bytes(b"not a program")
    program._loaded.clear()
    assert float(program(jnp.arange(3.0), 2.0, power=2)) == 10.0
    assert store.counts == {"compiled": 2}
    store.finish_writing()
    assert path.read_bytes() != b"not a program"


def test_a_program_that_fails_to_run_falls_back_to_jit(store):
    program = xla.jit(square_sum, static_argnames=("power",))
    program(jnp.arange(3.0), 2.0, power=2)
    store.finish_writing()  # files are checked and written in the background
    (path,) = store._root.glob("*.bin")

    def broken(*args):
        raise RuntimeError("a bad executable")

    for loaded in program._loaded.values():
        loaded.compiled = broken
    with pytest.warns(RuntimeWarning, match="failed to run"):
        assert float(program(jnp.arange(3.0), 2.0, power=2)) == 10.0
    assert not path.exists() and store._broken
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert float(program(jnp.arange(3.0), 2.0, power=2)) == 10.0  # plain jit, quietly


def test_a_jax_that_cannot_read_programs_back_keeps_jit_and_its_cache(store, monkeypatch):
    def fails(*args):
        raise RuntimeError("Compilation does not support serialization")

    from jax.experimental import serialize_executable

    monkeypatch.setattr(program_store, "_works", None)
    monkeypatch.setattr(serialize_executable, "serialize", fails)
    program = xla.jit(square_sum, static_argnames=("power",))
    assert float(program(jnp.arange(3.0), 2.0, power=2)) == 10.0
    store.finish_writing()  # files are checked and written in the background
    assert store.counts == {"plain": 1} and not list(store._root.glob("*.bin"))
    assert program_store._works is False


def test_the_round_trip_check_passes_here():
    assert program_store.store_works()


def test_a_students_step_function_is_never_stored(store):
    arm = ik.planar_chain([1.0, 1.0])
    res = ik.solve(arm, [1.0, 1.0], [0.3, 0.3], method=lambda J, e: 0.5 * J.T @ e)
    assert res.converged
    assert store.counts == {"plain": 1}


def test_a_patched_module_turns_the_store_off(store, monkeypatch):
    arm = ik.planar_chain([1.0, 1.0])
    assert program_store.patched_modules() == []
    monkeypatch.setattr(ik.jt, "jt_step", lambda J, e: J.T @ e)  # a notebook's patch
    assert program_store.patched_modules() == ["ikteach.jt"]
    ik.solve(arm, [1.0, 1.0], [0.3, 0.3], method="jt")
    assert store.counts == {"plain": 1}


def test_a_stored_function_called_while_tracing_is_traced_into_the_caller(store):
    program = xla.jit(square_sum, fast_compile=False, static_argnames=("power",))
    caller = jax.jit(lambda x: program(x, 2.0, power=2) + 1.0)
    assert float(caller(jnp.arange(3.0))) == 11.0
    assert float(jax.grad(lambda x: program(x, 1.0, power=2))(3.0)) == 6.0
    store.finish_writing()  # files are checked and written in the background
    assert store.counts == {} and not list(store._root.glob("*.bin"))


def test_exact_programs_are_compiled_as_jax_jit_does(store):
    """fast_compile=False: no compiler options (JAX refuses those on a nested call, so the
    nested call shows them), and results equal plain jax.jit's to the bit."""
    fast = xla.jit(square_sum, static_argnames=("power",))
    exact = xla.jit(square_sum, fast_compile=False, static_argnames=("power",))
    if xla.COMPILER_OPTIONS:
        with pytest.raises(ValueError, match="compiler_options"):
            jax.jit(lambda x: fast(x, 1.0, power=2))(jnp.arange(3.0))
    assert float(jax.jit(lambda x: exact(x, 1.0, power=2))(jnp.arange(3.0))) == 5.0
    arm, theta = ik.buss_trees.double_y_tree(), np.linspace(-1.0, 1.0, 25)
    function = ik.tree_jacobian_autodiff.__wrapped__
    ours = np.asarray(xla.jit(function, fast_compile=False)(arm, theta))
    plain = np.asarray(jax.jit(function)(arm, theta))
    assert store.counts == {"compiled": 1} and ours.tobytes() == plain.tobytes()


def test_programs_are_read_ahead_in_the_order_they_were_used(store):
    """The store notes which program followed which; in a new process, asking for one starts
    loading those that followed it last time, and a changed order is noted again."""
    program = xla.jit(square_sum, static_argnames=("power",))
    sizes = [3, 4, 5, 6]
    for n in sizes:
        program(jnp.arange(float(n)), 1.0, power=2)
    store.finish_writing()  # files are checked and written in the background
    assert len(list(store._root.glob("*.next"))) == 3
    program._loaded.clear()  # as in a new process
    store._previous = None
    store._asked.clear()
    assert float(program(jnp.arange(3.0), 1.0, power=2)) == 5.0
    first = store._previous
    assert len(store._ahead) == 3  # 4, 5 and 6 are loading
    for n in sizes[1:]:
        assert float(program(jnp.arange(float(n)), 1.0, power=2)) == sum(k * k for k in range(n))
    assert store.ahead_counts["ready"] + store.ahead_counts["waited"] == 3
    assert store.counts["loaded"] == 4 and not store._ahead
    store._follow(first)  # 4, 5 and 6 follow it, but this process has them already
    assert not store._ahead


def test_a_program_read_ahead_for_other_arguments_is_not_used(store):
    program = xla.jit(square_sum, static_argnames=("power",))
    program(jnp.arange(3.0), 1.0, power=2)
    program(jnp.arange(4.0), 1.0, power=2)
    store.finish_writing()  # files are checked and written in the background
    (first,) = [p for p in store._root.glob("*.next")]
    second = store._root / (first.read_text() + ".bin")
    other = program_store.pickle.loads(second.read_bytes())
    foreign = (other[0], jax.tree_util.tree_structure(((1.0,), {})), *other[2:])
    second.write_bytes(program_store.pickle.dumps(foreign))  # claims another input structure
    program._loaded.clear()
    store._previous = None
    store._asked.clear()
    program(jnp.arange(3.0), 1.0, power=2)
    assert float(program(jnp.arange(4.0), 1.0, power=2)) == 14.0
    assert store.ahead_counts["unused"] == 1 and store.counts["compiled"] == 3


def test_a_committed_array_goes_to_plain_jit(store):
    program = xla.jit(square_sum, static_argnames=("power",))
    x = jax.device_put(jnp.arange(3.0), jax.devices()[0])
    assert float(program(x, 2.0, power=2)) == 10.0
    assert store.counts == {"plain": 1}


def outer_scale():
    return 2.0


@pytest.mark.parametrize("value, stable", [
    (1, True), (1.5, True), ("dls", True), (None, True), ((1, "a", 2.5), True),
    ({1: [2, 3]}, True), (np.arange(3.0), True), (np.float64(0.5), True), (np.add, True),
    (ik.solve, True), (ik.METHODS["dls"], True), (math.hypot, True),
    (ik.planar_chain([1.0]), True),  # an ikteach dataclass: its fields, arrays by content
    (lambda x: x, False),  # no name
    (outer_scale, False),  # a name, but not in ikteach: its body may differ in the next process
    (object(), False), (jnp.linalg.norm, False),  # no stable text: plain jit decides
])
def test_describe_names_only_values_it_can_name_in_every_process(value, stable):
    assert (program_store.describe(value) is not None) == stable


def test_describe_tells_values_apart():
    d = program_store.describe
    assert d(np.arange(3.0)) == d(np.arange(3.0)) != d(np.arange(3.0) + [0, 0, 1e-12])
    assert len({d(1), d(1.0), d(True), d("1")}) == 4
    assert d((1, 2)) != d([1, 2])
    assert d(ik.METHODS["jt"]) != d(ik.METHODS["dls"])
    assert d({"a": 1, "b": 2}) == d({"b": 2, "a": 1})


def test_every_ikteach_module_is_unpatched_after_import():
    for name in ("scene", "workspace", "demo", "plot", "character_scene", "grade"):
        getattr(ik, name, None)
    assert program_store.patched_modules() == []


def test_programs_that_call_lapack_are_told_apart():
    """A stored program calling LAPACK needs jaxlib's LAPACK set up before it runs (else a
    crash: tests/ second-process test loads a DLS pose solve); others skip importing scipy."""
    with program_store._without_jax_cache():  # as the store compiles (one from JAX's cache
        svd = jax.jit(lambda a: jnp.linalg.svd(a)[1]).lower(jnp.eye(3)).compile()  # has no text)
        product = jax.jit(lambda a: a @ a).lower(jnp.eye(3)).compile()
    assert program_store.calls_lapack(svd) and not program_store.calls_lapack(product)
