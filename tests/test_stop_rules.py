"""The stop rules and what each status means: the default ("motion") rule decides alike at
every scale, the report's sum |delta_theta| does not; "slow" is still closing in; a stop that is
not at a minimum of ||e|| says why ("singular", "damped"); DLS at lambda = 0 on a singular J
stops "diverged" at its start and never returns NaN."""
import importlib

import numpy as np
import pytest

import ikteach as ik
from ikteach.core import stop_rules

solve_module = importlib.import_module("ikteach.core.solve")

START = np.array([0.1, 0.2, 0.3])
METHODS = list(ik.core.methods.METHODS)
SCALES = [1e-3, 1e-2, 1.0, 1e2, 1e3]
REACHABLE, UNREACHABLE = np.array([2.5, 0.5]), np.array([3.5, 1.0])


def scaled(scale, target, method, rule="motion", **kw):
    arm = ik.planar_chain([scale] * 3)
    return ik.solve(arm, np.asarray(target) * scale, START, method=method, stop_rule=rule, **kw)


@pytest.mark.parametrize("scale", SCALES)
@pytest.mark.parametrize("method", METHODS)
def test_the_scale_table_with_the_defaults(method, scale):
    """No tol, damping or stall_tol given: the defaults scale with the arm."""
    near = ik.solve(ik.planar_chain([scale] * 3), REACHABLE * scale, START, method=method)
    far = ik.solve(ik.planar_chain([scale] * 3), UNREACHABLE * scale, START, method=method)
    assert near.status == "converged", near
    # the pseudoinverse never settles out of reach (the report's finding): at every scale
    assert far.status == ("max_iter" if method == "pinv" else "stalled"), far
    one = [ik.solve(ik.planar_chain([1.0] * 3), t, START, method=method) for t in (REACHABLE, UNREACHABLE)]
    assert (near.iterations, far.iterations) == (one[0].iterations, one[1].iterations)


@pytest.mark.parametrize("scale", [1e-3, 1e3])
@pytest.mark.parametrize("method", METHODS)
def test_the_scale_table_with_tol_and_damping_scaled_by_hand(method, scale):
    kw = dict(tol=1e-3 * scale, damping=0.5 * scale)
    assert scaled(scale, REACHABLE, method, **kw).status == "converged"
    assert scaled(scale, UNREACHABLE, method, **kw).status in ("stalled", "max_iter" if method == "pinv" else "-")


def test_defaults_are_lengths_that_scale_with_the_arm():
    options = ik.Options().resolved(3.0, 3)  # three unit links: L = 3
    assert options.tol == 1e-3 and options.stall_tol == 1e-5
    assert ik.DLS().resolved(3.0).damping == 0.5
    # the 1 mm arm: converges by default (it ran to max_iter with absolute defaults)
    res = ik.solve(ik.planar_chain([1e-3] * 3), [2e-3, 1e-3], np.zeros(3))
    assert res.status == "converged" and res.iterations < 20, res


def test_the_reports_rule_depends_on_the_unit_of_length():
    kw = lambda s: dict(tol=1e-3 * s, damping=0.5 * s, stall_tol=1e-5 * 3 * s)  # the report's threshold
    its = [scaled(s, UNREACHABLE, "jt", "joint_steps", **kw(s)).iterations for s in (0.01, 1.0, 100.0)]
    assert its[0] > its[1] > its[2], its
    big = scaled(100.0, REACHABLE, "jt", "joint_steps", **kw(100.0))  # reachable, yet stopped short
    assert big.status == "slow" and big.error > 1e-3 * 100
    assert scaled(100.0, REACHABLE, "jt", "motion", **kw(100.0)).converged


def test_slow_means_the_error_still_shrinks_and_stalled_that_it_levelled_off():
    kw = dict(tol=0.1, damping=50.0, stall_tol=3e-3, stop_rule="joint_steps")
    arm = ik.planar_chain([100.0] * 3)
    slow = ik.solve(arm, [250.0, 50.0], START, method="jt", **kw)
    far = ik.solve(arm, [350.0, 100.0], START, method="jt", **kw)
    assert slow.status == "slow" and far.status == "stalled"
    progress = lambda r: float(stop_rules.relative_progress(r.trace.error[-2], r.trace.error[-1]))
    assert progress(slow) > stop_rules.SLOW_PROGRESS > progress(far)


@pytest.mark.parametrize("method", METHODS)
def test_a_singular_start_says_so_and_a_nudge_gets_going(method):
    """Straight arm, target on its own line: J cannot see the error, every method stops at once."""
    arm = ik.planar_chain([1.0] * 3)
    stuck = ik.solve(arm, [2.0, 0.0], np.zeros(3), method=method)
    assert (stuck.status, stuck.iterations) == ("singular", 1), stuck
    assert ik.solve(arm, [2.0, 0.0], [0.0, 0.1, 0.0], method=method).converged


@pytest.mark.parametrize("method", ["jt", "pinv", "dls", "sdls"])
def test_singular_says_nothing_about_reach(method):
    """The same saddle with the target behind the arm, 2 beyond its reach (the status glossary)."""
    arm = ik.planar_chain([1.0] * 3)
    behind = ik.solve(arm, [-5.0, 0.0], np.zeros(3), method=method)
    assert (behind.status, behind.iterations, behind.error) == ("singular", 1, 8.0), behind
    nudged = ik.solve(arm, [-5.0, 0.0], [0.0, 0.1, 0.0], method=method)
    assert not nudged.converged and nudged.error > 2.0 - 1e-3, nudged


@pytest.mark.parametrize("kw", [dict(damping=1e3), dict(max_step=1e-6)])
def test_steps_cut_to_nothing_by_damping_or_caps_say_damped(kw):
    res = ik.solve(ik.planar_chain([1.0] * 3), REACHABLE, START, **kw)
    assert res.status == "damped" and res.error > 0.5, res


def test_batch_gives_the_same_statuses_as_solve_on_the_queue_path():
    arm = ik.planar_chain([1.0] * 3)
    targets = np.array([[2.0, 0.0], [3.5, 1.0], [2.5, 0.5], [0.0, -4.0]] * 3)  # 12 rows: the queue
    starts = np.array([np.zeros(3), START, START, START] * 3)
    # [0, -4]: 1 beyond the reach, DLS with lambda 0.5 < lambda* never settles (lecture 05, 3b)
    expect = {0.5: ["singular", "stalled", "converged", "max_iter"], 1e3: ["singular", "damped", "damped"]}
    for damping, statuses in expect.items():
        res = ik.solve_batch(arm, targets, starts, damping=damping)
        one = [ik.solve(arm, t, q, damping=damping) for t, q in zip(targets, starts)]
        assert list(res.status) == [r.status for r in one]
        assert list(res.iterations) == [r.iterations for r in one]
        assert list(res.status[: len(statuses)]) == statuses


def test_new_statuses_are_appended():
    assert solve_module.STATUSES[:5] == ("running", "converged", "stalled", "max_iter", "diverged")
    assert solve_module.STATUSES[5:] == ("slow", "singular", "damped", "fixed_point")


def test_dls_without_damping_at_a_singular_start_stops_diverged_never_nan():
    """lambda = 0 is the plain formula J^T (J J^T)^-1 e: at a singular J it has no answer, the
    step is not finite and the loop stops "diverged" at the start, which it keeps."""
    planar = ik.planar_chain([1.0] * 3)
    spatial = ik.serial_chain([[0, 0, 1], [0, 1, 0], [0, 1, 0]], [[0, 0, 0.5], [0, 0, 1], [0, 0, 1]])
    ur5 = ik.core.robots.ur5()
    cases = [(planar, [2.0, 0.5], np.zeros(3)),                         # 2 rows
             (spatial, [0.5, 0.3, 1.5], np.zeros(3)),                   # 3 rows
             (ur5, np.asarray(ik.fk_pose(ur5, np.full(6, 0.4))), np.zeros(6))]  # 6 rows
    for arm, target, start in cases:
        J = np.asarray(ik.jacobian(arm, start, full=len(np.shape(target)) == 2))
        assert np.linalg.svd(J, compute_uv=False)[-1] < 1e-12  # the start is singular
        res = ik.solve(arm, target, start, damping=0.0, max_iter=300)
        assert (res.status, res.iterations) == ("diverged", 0), res
        np.testing.assert_array_equal(res.theta, start)
        assert ik.solve(arm, target, start, damping=0.05, max_iter=300).status == "converged"


def test_dls_step_is_the_plain_formula():
    rng = np.random.default_rng(0)
    for m in (2, 3, 6):
        J, e = rng.normal(size=(m, 7)), rng.normal(size=m)
        for lam in (0.0, 1e-3, 0.5):
            plain = J.T @ np.linalg.solve(J @ J.T + lam**2 * np.eye(m), e)
            np.testing.assert_allclose(ik.dls_step(J, e, lam), plain, rtol=1e-9)



def test_unknown_stop_rule_names_the_parameter():
    with pytest.raises(ValueError, match="stop_rule"):
        ik.solve(ik.planar_chain([1.0, 1.0]), [1.0, 1.0], [0.0, 0.0], stop_rule="sum")
