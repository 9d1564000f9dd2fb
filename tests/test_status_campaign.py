"""Every status checked against its own definition on a seeded campaign (issue 40): 432 solves,
planar arms with links of very different lengths at scales 1e-3..1e3, every method, damping,
caps and clamps, reachable and unreachable targets, and UR5 poses with priority levels.

The judge is written here, apart from stop_rules.stall_kind: a downhill run of 200 damped
steps (ik.dls_step, or ik.priority_step for two levels; lambda adapted as in Levenberg-Marquardt;
no cap on the turn), each kept only when some level falls while no level before it is a visible
change above its start. A status is checked as its definition says
(ikteach/core/loop.py). A visible change: more than tol and more than 1e-3 ||e||. A gain: some
level falls by a visible change while no level before it rises by one, or ||e|| gets below tol. "damped",
"fixed_point" and "slow": the judge gains ("slow" also: the last step removed more than
SLOW_PROGRESS of ||e||); "stalled" and "singular": the judge does not gain twice that much
(no level falls by two visible changes; the solver looks 30 steps ahead, the judge 200, and in
a long flat valley the extra steps gain a little more: measured, 1.02 tol from 133 tol), and
"singular" also has a clearly negative Hessian of 1/2 ||e_0||^2; "converged" - ||e|| < tol at theta;
"max_iter" - max_iter steps taken. No solve returns NaN.
"""
import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import ikteach as ik
from ikteach.core import stop_rules
from ikteach._runtime import jit as xla
from ikteach.core.tasks import task_for

SEED = 40
GAIN = 1e-3  # a gain counts above GAIN ||e|| and above tol (the statuses' definition)


@functools.partial(xla.jit, static_argnames=("task", "rows", "steps"), light=True)
def judge_ends(task, rows, arm, targets, thetas, tol, steps=200):
    """A vmapped downhill run from each theta (returns where it ends): damped steps,
    ik.dls_step for one level and ik.priority_step for two, lambda adapted as in
    Levenberg-Marquardt, each step kept only when some level falls while no level before it
    is a visible change above its start. The arm is an argument: one program per number of
    joints and targets, whatever the lengths."""
    rows = [jnp.asarray(r) for r in rows]

    def run(target, theta):
        norms = lambda q: jnp.stack([jnp.linalg.norm(task.error(arm, target, q)[r]) for r in rows])
        e0 = task.error(arm, target, theta)
        start = norms(theta)
        visible = jnp.maximum(GAIN * jnp.linalg.norm(e0), tol)
        sigma = jnp.linalg.norm(task.jacobian(arm, theta), 2)

        def step(q, lam):
            J, e = task.jacobian(arm, q), task.error(arm, target, q)
            if len(rows) == 1:
                return ik.dls_step(J, e, lam)
            return ik.priority_step(J[rows[0]], e[rows[0]], J[rows[1]], e[rows[1]], lam)

        def one(_, carry):
            q, current, f = carry
            trial = q + step(q, f * sigma)
            after = norms(trial)
            held = jnp.concatenate([jnp.ones(1, bool), (after <= start + visible)[:-1]])
            kept = jnp.any((after < current) & (jnp.cumprod(held) > 0))
            return (jnp.where(kept, trial, q), jnp.where(kept, after, current),
                    jnp.where(kept, f / 3, f * 2))

        return jax.lax.fori_loop(0, steps, one, (theta, start, 1e-2))[0]

    return jax.vmap(run)(targets, thetas)


@functools.partial(xla.jit, static_argnames=("task",), light=True)
def errors(task, arm, targets, thetas):
    return jax.vmap(lambda t, q: task.error(arm, t, q))(targets, thetas)


@functools.partial(xla.jit, static_argnames=("task", "rows"), light=True)
def lowest_curvatures(task, rows, arm, targets, thetas):
    """Level 0's lowest Hessian eigenvalue of 1/2 ||e_0||^2 at each theta, over sigma_max^2."""
    def lowest(t, q):
        half = lambda p: 0.5 * jnp.sum(task.error(arm, t, p)[jnp.asarray(rows[0])] ** 2)
        sigma = jnp.linalg.norm(task.jacobian(arm, q), 2)
        return jnp.linalg.eigvalsh(jax.hessian(half)(q))[0] / sigma**2

    return jax.vmap(lowest)(targets, thetas)


def level_norms(E, rows):
    return np.stack([np.linalg.norm(E[:, r], axis=1) for r in rows], axis=1)


def judged(task, arm, targets, thetas, rows, tol):
    """For each row: does the judge gain (the definition above), does it gain twice that, and
    is level 0's Hessian clearly negative somewhere (a saddle)?"""
    rows = tuple(tuple(int(i) for i in r) for r in rows)
    ends = np.asarray(judge_ends(task, rows, arm, targets, thetas, tol))
    E0, E1 = np.asarray(errors(task, arm, targets, thetas)), np.asarray(errors(task, arm, targets, ends))
    before, after = level_norms(E0, rows), level_norms(E1, rows)
    scale = np.linalg.norm(E0, axis=1, keepdims=True)
    fall = before - after
    visible = np.maximum(GAIN * scale, tol)
    held = np.cumprod(np.concatenate([np.ones((len(fall), 1)), fall[:, :-1] >= -visible], 1), 1)
    gain, double = (np.any((fall > m * visible) & (held > 0), axis=1) for m in (1, 2))
    reached = np.linalg.norm(E1, axis=1) < tol  # reached: a gain under either margin
    gain, double = gain | reached, double | reached
    curvature = np.asarray(lowest_curvatures(task, rows, arm, targets, thetas))
    return gain, double, curvature < -1e-6


def check_statuses(arm, targets, starts, res, rows, tol, max_iter=1000, solve_again=None):
    """Each row's status against its definition; returns the statuses (for the counts)."""
    task = task_for(arm, targets.shape[1:])
    assert np.all(np.isfinite(res.theta)) and np.all(np.isfinite(res.error))
    E = np.asarray(errors(task, arm, targets, res.theta))
    converged = np.linalg.norm(E, axis=1) < tol
    np.testing.assert_array_equal(res.status == "converged", converged)
    assert np.all(res.iterations[res.status == "max_iter"] == max_iter)
    looked = np.isin(res.status, ["stalled", "singular", "damped", "fixed_point", "slow"])
    if looked.any():
        # judged on every row (one program per arm size and batch), read where it looked
        gain, big_gain, saddle = (v[looked] for v in judged(task, arm, targets, res.theta, rows, tol))
        status = res.status[looked]
        wrong = np.where(np.isin(status, ["stalled", "singular"]), big_gain, ~gain)
        wrong |= (status == "singular") & ~saddle
        assert not wrong.any(), [(s, k) for s, k in zip(status[wrong], np.flatnonzero(looked)[wrong])]
    for k in np.flatnonzero(res.status == "slow"):  # "slow": the last step still removed a fraction
        one = solve_again(targets[k], starts[k])
        assert one.status == "slow"
        assert stop_rules.still_progressing(one.trace.error[-2], one.trace.error[-1])
    return list(res.status)


def planar_groups(rng):
    """Twelve arms (2-5 links of lengths spread over three decades, scale 1e-3..1e3), one
    method each, 24 targets each (radius 0.05..1.4 times the reach, random starts)."""
    methods = [("jt", {}), (ik.Pinv(rcond=0.01), {}), ("dls", {}), ("sdls", {}), ("ccd", {}),
               ("fabrik", {}), ("pinv", {}), ("heavy", {}), ("dls", {"max_step": 1e-3}),
               ("dls", {"clamp": "small"}), ("jt", {"stop_rule": "joint_steps"}), ("dls", {})]
    for k, (method, kw) in enumerate(methods):
        n = int(rng.integers(2, 6))
        scale = 10 ** rng.uniform(-3, 3)
        lengths = 10 ** rng.uniform(-2.5, 0.5, n) * scale
        arm, L = ik.planar_chain(lengths), float(np.sum(lengths))
        if method == "heavy":
            method = ik.DLS(damping=L * 10 ** rng.uniform(-1, 1))
        if kw.get("clamp") == "small":
            kw = {"clamp": L * 10 ** rng.uniform(-2, -0.5)}
        phi = rng.uniform(-np.pi, np.pi, 24)
        targets = L * rng.uniform(0.05, 1.4, (24, 1)) * np.stack([np.cos(phi), np.sin(phi)], 1)
        yield arm, targets, rng.uniform(-np.pi, np.pi, (24, n)), method, kw


def test_every_planar_status_means_what_it_says():
    rng = np.random.default_rng(SEED)
    seen = []
    for arm, targets, starts, method, kw in planar_groups(rng):
        res = ik.solve_batch(arm, targets, starts, method=method, **kw)
        again = lambda t, q: ik.solve(arm, t, q, method=method, **kw)
        seen += check_statuses(arm, targets, starts, res, [np.arange(2)],
                               float(ik.reach(arm)) / 3000, solve_again=again)
    counts = {s: seen.count(s) for s in set(seen)}
    assert len(seen) == 288
    assert {"converged", "stalled", "damped", "max_iter"} <= set(counts), counts


@pytest.mark.parametrize("levels", [(1, 0), (0, 1)])
def test_every_prioritised_status_means_what_it_says(levels):
    """UR5 poses (a third pushed out of reach) with position and orientation at different
    priorities: a stall is judged by what a later level can still gain."""
    rng = np.random.default_rng(SEED + levels[0])
    U = ik.core.robots.ur5()
    goals = rng.uniform(-np.pi, np.pi, (36, 6))
    T = np.stack([np.asarray(ik.fk_pose(U, g)) for g in goals])
    T[::3, :3, 3] *= rng.uniform(1.2, 2.5, (12, 1))
    starts = goals + rng.uniform(-1.0, 1.0, goals.shape)
    seen = []
    for damping in (0.2, 0.5):
        method = ik.DLS(damping=damping)
        res = ik.solve_batch(U, T, starts, method=method, levels=levels)
        rows = [np.arange(3), np.arange(3, 6)][:: 1 if levels == (0, 1) else -1]
        again = lambda t, q: ik.solve(U, t, q, method=method, levels=levels)
        seen += check_statuses(U, T, starts, res, rows, float(ik.reach(U)) / 3000, solve_again=again)
    assert "converged" in seen and {"stalled", "damped", "slow"} & set(seen), seen
