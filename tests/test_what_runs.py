"""What a lecture prints is what runs: ik.solve and ik.solve_batch call the step function each
method's lecture prints (counted by wrapping it, with JAX's caches cleared first so that every
program is traced again), and run the loop of ikteach/core/loop.py."""
import functools

import jax
import numpy as np
import pytest

import ikteach as ik
from ikteach.core import ccd, dls, fabrik, jt, loop, pinv, sdls

PLANAR = ik.planar_chain([1.0, 0.8, 0.5])
SPATIAL = ik.serial_chain([[0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 1, 0]],
                          [[0, 0, 0.4], [0.5, 0, 0], [0, 0.4, 0], [0.3, 0, 0]])
# method -> (module, the function its lecture prints) on a planar arm and on a spatial one
PRINTED = {
    "jt": ((jt, "jt_step"), (jt, "jt_step")),                    # lecture 02
    "pinv": ((pinv, "pinv_two_rows"), (pinv, "pinv_step")),      # lecture 03 prints both
    "dls": ((dls, "dls_step_small"), (dls, "dls_step_small")),   # lecture 04 prints both
    "sdls": ((sdls, "sdls_step"), (sdls, "sdls_step")),          # lecture 08
    "ccd": ((ccd, "ccd_angle"), (ccd, "ccd_angle")),             # lecture 08
    "fabrik": ((fabrik, "fabrik_forward"), (fabrik, "fabrik_forward")),  # lecture 08
}


def counting(monkeypatch, module, name):
    calls = []
    original = getattr(module, name)

    @functools.wraps(original)
    def wrapper(*args, **kwargs):
        calls.append(1)
        return original(*args, **kwargs)

    monkeypatch.setattr(module, name, wrapper)
    return calls


def test_every_registered_method_has_its_printed_function_here():
    assert set(PRINTED) == set(ik.core.methods.METHODS)


@pytest.mark.parametrize("method", list(PRINTED))
@pytest.mark.parametrize("arm", [PLANAR, SPATIAL], ids=["planar", "spatial"])
def test_solve_and_solve_batch_call_the_printed_step(method, arm, monkeypatch):
    module, name = PRINTED[method][arm.dim == 3]
    rng = np.random.default_rng(1)
    targets = np.stack([np.asarray(ik.fk(arm, q)) for q in rng.uniform(-1, 1, (12, arm.n_joints))])
    start = np.full(arm.n_joints, 0.2)
    for run in (lambda: ik.solve(arm, targets[0], start, method=method, max_iter=20),
                lambda: ik.solve_batch(arm, targets, start, method=method, max_iter=20)):
        jax.clear_caches()
        calls = counting(monkeypatch, module, name)
        passes = counting(monkeypatch, loop, "stop_rule")  # looked up by loop.iterate
        run()
        assert calls and passes, (method, name)
        monkeypatch.undo()
