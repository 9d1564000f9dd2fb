"""ikteach._runtime.jit: the compiler options of the whole-loop programs change how fast they compile,
never what they compute."""
import json
import os
import subprocess
import sys

import numpy as np

import ikteach as ik
from ikteach._runtime import jit as xla

SCRIPT = """
import json, numpy as np, ikteach as ik
from ikteach._runtime import jit as xla
ik.notebook.compilation_cache()  # as in the tests' own process: a second run compiles nothing
arm = ik.planar_chain([1.0, 0.7, 0.4])
g = np.linspace(-2.3, 2.3, 24)
targets = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
out = {"options": xla.compiler_options(), "light": xla.compiler_options(light=True)}
for method in ("dls", "jt", "sdls", "ccd"):
    b = ik.solve_batch(arm, targets, [0.3, 0.2, 0.1], method=method, max_iter=150)
    r = ik.solve(arm, [1.2, 0.9], [0.3, 0.2, 0.1], method=method, clamp=0.5)
    far = ik.solve(arm, [2.5, 0.6], [0.3, 0.2, 0.1], method=method)  # out of reach: named light
    out[method] = [b.status.tolist(), b.iterations.tolist(), b.theta.tolist(),
                   r.status, r.iterations, r.theta.tolist(), far.status]
print(json.dumps(out))
"""


def run(env_value):
    env = dict(os.environ, **{xla.OPTIONS_ENV: env_value})
    done = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                          env=env, timeout=300, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def test_an_unknown_option_is_refused_not_fatal():
    assert not xla.supported({"xla_cpu_no_such_option": True})
    assert xla.supported({})


def _jaxlib_version():
    import jaxlib

    return tuple(int(v) for v in jaxlib.__version__.split(".")[:2])


def test_the_locked_jaxlib_takes_the_fast_compile_option():
    """The lock's jaxlib for Python 3.11 (0.10) knows the option; its jaxlib for Python >= 3.12
    (0.12) does not, and then every program compiles as plain jax.jit does."""
    if _jaxlib_version() < (0, 12):
        assert xla.supported(xla.FAST_COMPILE)
        assert xla.compiler_options() == xla.FAST_COMPILE
        assert xla.compiler_options(light=True) == {**xla.FAST_COMPILE, **xla.LIGHT_COMPILE}
    else:
        assert not xla.supported(xla.FAST_COMPILE) and xla.compiler_options() is None
    assert xla.supported(xla.LIGHT_COMPILE)  # a long-standing option of XLA's


def test_with_and_without_the_options_every_solve_ends_the_same():
    fast, plain = run("on"), run("off")
    on = xla.FAST_COMPILE if xla.supported(xla.FAST_COMPILE) else None  # see the test above
    assert fast["options"] == on and plain["options"] is None and plain["light"] is None
    assert xla.LIGHT_COMPILE.items() <= fast["light"].items()
    for method in ("dls", "jt", "sdls", "ccd"):
        (bs, bi, bt, rs, ri, rt, rf), (ps, pi, pt, qs, qi, qt, qf) = fast[method], plain[method]
        assert bs == ps and bi == pi and (rs, ri, rf) == (qs, qi, qf), method
        np.testing.assert_allclose(bt, pt, atol=1e-9, err_msg=method)
        np.testing.assert_allclose(rt, qt, atol=1e-9, err_msg=method)


def test_jit_takes_decorator_arguments_and_keeps_the_function():
    @xla.jit
    def double(x):
        return 2 * x

    from functools import partial

    @partial(xla.jit, static_argnames=("k",))
    def power(x, k):
        return x**k

    assert float(double(3.0)) == 6.0 and float(power(2.0, k=3)) == 8.0
    assert double.__wrapped__.__name__ == "double"
    assert np.isfinite(ik.solve(ik.planar_chain([1.0, 1.0]), [1.0, 1.0], [0.1, 0.2]).error)


def test_quick_jit_runs_alone_inside_a_trace_and_keeps_its_own_errors():
    import jax
    import pytest

    arm, q = ik.planar_chain([1.0, 0.5, 0.25]), np.array([0.3, -0.2, 0.4])
    alone = np.asarray(ik.fk(arm, q))  # compiled with the options
    assert ik.fk.__wrapped__.__name__ == "fk" and ik.fk.__module__ == "ikteach.core.kinematics"
    assert isinstance(ik.fk, xla.QuickProgram) and isinstance(ik.jacobian, xla.QuickProgram)
    # inside another program: traced (inlined), and with constants only (no options there)
    np.testing.assert_allclose(jax.jit(lambda t: ik.fk(arm, t))(q), alone, rtol=1e-14)
    np.testing.assert_allclose(jax.jit(lambda: ik.fk(arm, q))(), alone, rtol=1e-14)
    np.testing.assert_allclose(jax.jacfwd(lambda t: ik.fk(arm, t))(q), ik.jacobian(arm, q),
                               atol=1e-12)
    assert ik.jacobian(arm, q, full=True).shape == (3, 3)  # a static argument
    with pytest.raises(ValueError, match="theta: expected shape"):
        ik.fk(arm, np.zeros(4))


def test_past_the_bound_the_caches_are_cleared_and_results_stay_the_same(monkeypatch):
    """The program bound: past max_programs() distinct programs JAX's caches are cleared; the
    solves after it give the same answers as before; IKTEACH_MAX_PROGRAMS=0 turns it off."""
    arm = ik.planar_chain([1.0, 0.7, 0.4])
    before = ik.solve(arm, [1.2, 0.9], [0.3, 0.2, 0.1], method="jt")
    monkeypatch.setenv(xla.BOUND_ENV, "2")
    clears = xla.clears[0]
    for n in (2, 4, 5):  # new programs: past the bound of 2
        ik.solve(ik.planar_chain([1.0] * n), [1.0, 0.5], np.zeros(n), method="jt")
    assert xla.clears[0] > clears
    after = ik.solve(arm, [1.2, 0.9], [0.3, 0.2, 0.1], method="jt")
    assert (after.status, after.iterations) == (before.status, before.iterations)
    np.testing.assert_array_equal(after.theta, before.theta)
    monkeypatch.setenv(xla.BOUND_ENV, "0")
    clears = xla.clears[0]
    for n in (6, 7, 9):
        ik.solve(ik.planar_chain([1.0] * n), [1.0, 0.5], np.zeros(n), method="jt")
    assert xla.clears[0] == clears
