"""The stall rules: the report's sum |delta_theta| depends on the unit of length, the
end effector's motion does not; "slow" (still converging) is told apart from "stalled"."""
import importlib

import numpy as np
import pytest

import ikteach as ik
from ikteach.core import stop_rules

solve_module = importlib.import_module("ikteach.core.solve")

START = np.array([0.1, 0.2, 0.3])


def scaled(scale, target, method, rule):
    arm = ik.planar_chain([scale] * 3)
    return ik.solve(arm, np.asarray(target) * scale, START, method=method, tol=1e-3 * scale,
                    damping=0.5 * scale, stop_rule=rule)


@pytest.mark.parametrize("method", ["jt", "dls"])
def test_the_motion_rule_decides_the_same_at_every_scale(method):
    runs = [scaled(s, [3.5, 1.0], method, "motion") for s in (0.01, 1.0, 100.0)]
    assert {r.status for r in runs} == {"stalled"}
    assert len({r.iterations for r in runs}) == 1, [r.iterations for r in runs]


def test_the_reports_rule_depends_on_the_unit_of_length():
    its = [scaled(s, [3.5, 1.0], "jt", "joint_steps").iterations for s in (0.01, 1.0, 100.0)]
    assert its[0] > its[1] > its[2], its
    big = scaled(100.0, [2.5, 0.5], "jt", "joint_steps")  # reachable, yet stopped short
    assert big.status == "slow" and big.error > 1e-3 * 100
    assert scaled(100.0, [2.5, 0.5], "jt", "motion").converged


def test_slow_means_the_error_still_shrinks_and_stalled_that_it_levelled_off():
    arm = ik.planar_chain([100.0] * 3)
    slow = ik.solve(arm, [250.0, 50.0], START, method="jt", tol=0.1, damping=50.0)
    far = ik.solve(arm, [350.0, 100.0], START, method="jt", tol=0.1, damping=50.0)
    assert slow.status == "slow" and far.status == "stalled"
    progress = lambda r: float(stop_rules.relative_progress(r.trace.error[-2], r.trace.error[-1]))
    assert progress(slow) > stop_rules.SLOW_PROGRESS > progress(far)


def test_new_statuses_are_appended():
    assert solve_module.STATUSES[:5] == ("running", "converged", "stalled", "max_iter", "diverged")
    assert solve_module.STATUSES[solve_module.SLOW] == "slow"


def test_batch_takes_the_stop_rule_and_agrees_with_solve():
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    targets = np.array([[2.5, 0.5], [3.5, 1.0]])
    res = ik.solve_batch(arm, targets, START, method="dls", stop_rule="motion")
    one = [ik.solve(arm, t, START, method="dls", stop_rule="motion") for t in targets]
    assert list(res.status) == [r.status for r in one]
    assert list(res.iterations) == [r.iterations for r in one]


def test_unknown_stop_rule_names_the_parameter():
    with pytest.raises(ValueError, match="stop_rule"):
        ik.solve(ik.planar_chain([1.0, 1.0]), [1.0, 1.0], [0.0, 0.0], stop_rule="sum")
