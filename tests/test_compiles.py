"""No recompilation after the first solve of a given (method, arm shape, max_iter, target
kind): new targets, damping, tolerances, clamps and iteration counts compile nothing."""
import numpy as np
import pytest
from jax import monitoring

import ikteach as ik
from ikteach.core.kinematics import end_path
from ikteach._runtime.engine import TRACE_CHUNK

ARM = ik.planar_chain([1.0, 1.0, 1.0])
START = np.array([0.1, 0.2, 0.3])
METHODS = tuple(ik.core.methods.METHODS)
COMPILES = []


def _count(event, duration, fun_name="?", **kwargs):
    if event.endswith("backend_compile_duration"):
        COMPILES.append(fun_name)


monitoring.register_event_duration_secs_listener(_count)


@pytest.fixture(autouse=True)
def no_program_bound(monkeypatch):
    """The bound on compiled programs (ikteach/_runtime/jit.py) off: a worker that compiled many
    programs in earlier test files would otherwise clear JAX's caches in the middle of a count."""
    monkeypatch.setenv("IKTEACH_MAX_PROGRAMS", "0")


def varied_solves(rng, count):
    """count solves cycling through the methods with varied targets and settings."""
    results = []
    for k in range(count):
        results.append(ik.solve(
            ARM, rng.uniform(-3.5, 3.5, size=2), START, method=METHODS[k % len(METHODS)],
            max_iter=300, damping=rng.uniform(0.05, 1.5), tol=rng.choice([1e-2, 1e-3, 1e-5]),
            clamp=rng.choice([None, 0.3, 1.0]), max_step=rng.choice([None, 0.2])))
    return results


def test_the_counter_sees_a_compilation():
    before = len(COMPILES)
    ik.solve(ik.planar_chain([1.0] * 17), [1.0, 1.0], np.zeros(17))  # a shape no other test uses
    assert len(COMPILES) > before


def test_twenty_varied_solves_compile_nothing_new():
    rng = np.random.default_rng(3)
    for res in varied_solves(rng, len(METHODS)):  # the first solve of each method compiles
        end_path(ARM, res.trace.theta)
    before = len(COMPILES)
    results = varied_solves(rng, 20)
    for res in results:
        end_path(ARM, res.trace.theta)  # traces of every length: the demo draws them
    assert len(COMPILES) == before, COMPILES[before:]
    assert len({res.iterations for res in results}) > 5  # iteration counts did vary
    assert {res.status for res in results} >= {"converged", "stalled"}


@pytest.mark.parametrize("k", [1, 5, 128, 129, 300])
def test_end_path_in_blocks_equals_fk_row_by_row(k):
    thetas = np.random.default_rng(k).normal(size=(k, 3))
    want = np.array([np.asarray(ik.fk(ARM, q)) for q in thetas])
    np.testing.assert_allclose(end_path(ARM, thetas), want, atol=1e-12)


def _numpy_stop_step(J, e):  # a student's step: numpy, with the exercise-5 stop rule
    delta = 0.1 * np.asarray(J).T @ np.asarray(e)
    if np.abs(delta).sum() < 1e-3:
        raise ik.StopSolve()
    return delta


@pytest.mark.parametrize("stop_rule", ["joint_steps", "motion"])
def test_eager_solves_with_a_python_step_compile_nothing_new(stop_rule):
    ik.solve(ARM, [2.5, 0.5], START, method=_numpy_stop_step, max_iter=50, stop_rule=stop_rule)
    before = len(COMPILES)
    for target in ([2.0, 1.0], [4.0, 0.5], [1.0, -1.5]):  # reachable and out of reach
        ik.solve(ARM, target, START, method=_numpy_stop_step, max_iter=50, stop_rule=stop_rule)
    assert len(COMPILES) == before, COMPILES[before:]


def test_paths_of_any_length_track_with_one_program():
    """track runs paths CHUNK steps at a time: a new length compiles nothing, and a path's
    first steps are the same whatever follows them (across chunk boundaries too)."""
    from ikteach._runtime.engine import SCAN_CHUNK as CHUNK

    path = np.stack([np.linspace(1.0, 2.8, 2 * CHUNK + 9), np.linspace(0.5, 1.2, 2 * CHUNK + 9)], 1)
    whole = ik.track(ARM, path, START, method="dls", damping=0.2)
    assert whole.theta.shape == (path.shape[0] + 1, 3) and whole.error.shape == (path.shape[0],)
    before = len(COMPILES)
    for steps in (1, 7, CHUNK, CHUNK + 1, 2 * CHUNK + 3):
        part = ik.track(ARM, path[:steps], START, method="dls", damping=0.2)
        np.testing.assert_array_equal(part.theta, whole.theta[: steps + 1])
        np.testing.assert_array_equal(part.error, whole.error[:steps])
    assert len(COMPILES) == before, COMPILES[before:]


def test_a_new_max_iter_or_a_long_solve_compiles_nothing_new():
    """max_iter is traced: any value reuses the compiled loop, and a solve longer than one
    chunk of trace runs the same program again."""
    ik.solve(ARM, [1.5, 1.0], START, method="jt", max_iter=300)
    ik.solve_batch(ARM, np.array([[1.0, 1.0], [9.0, 0.0]]), START, method="jt", max_iter=300)
    before = len(COMPILES)
    chunk = TRACE_CHUNK
    for max_iter in (1, 2, chunk - 1, chunk, chunk + 1, 2 * chunk + 1, 4096, 10**6):
        res = ik.solve(ARM, [9.0, 0.0], START, method="jt", max_iter=max_iter, stall_tol=0)
        assert res.iterations == max_iter or res.status != "max_iter"
        assert res.trace.theta.shape == (res.iterations + 1, 3)
        assert res.trace.error.shape == (res.iterations + 1,)
        if max_iter > 4096:
            break
    ik.solve_batch(ARM, np.array([[1.0, 1.0], [9.0, 0.0]]), START, method="jt", max_iter=77)
    assert len(COMPILES) == before, COMPILES[before:]


def test_the_trace_follows_the_iterations_not_max_iter():
    """A target met at the start keeps one row of trace, whatever max_iter allows; above the
    cap max_iter is a ValueError naming it."""
    arm = ik.planar_chain([1.0] * 12)
    res = ik.solve(arm, np.asarray(ik.fk(arm, np.zeros(12))), np.zeros(12), max_iter=10**6)
    assert (res.status, res.iterations, res.trace.theta.shape) == ("converged", 0, (1, 12))
    with pytest.raises(ValueError, match="max_iter: expected at most"):
        ik.solve(arm, [1.0, 1.0], np.zeros(12), max_iter=2**40)


@pytest.mark.parametrize("method", METHODS)
def test_a_trace_across_chunks_is_the_trace_of_one_long_run(method):
    """Iterates recorded across chunk boundaries: each row is the step from the row before,
    and the errors are the errors of those rows."""
    res = ik.solve(ARM, [2.9, 0.4], START, method=method, max_iter=2 * TRACE_CHUNK + 50,
                   stall_tol=0, tol=1e-12)
    assert res.iterations > TRACE_CHUNK or res.status != "max_iter"
    for k in range(res.iterations + 1):
        err = np.linalg.norm(np.array([2.9, 0.4]) - np.asarray(ik.fk(ARM, res.trace.theta[k])))
        assert abs(err - res.trace.error[k]) < 1e-12, k
    np.testing.assert_array_equal(res.trace.theta[-1], res.theta)


def test_new_pose_weights_compile_nothing_new():
    """PoseTask's weights are traced data: a new (position, orientation) pair reuses the loop."""
    ur5 = ik.core.robots.ur5()
    target = np.asarray(ik.fk_pose(ur5, np.full(6, 0.4)))
    kw = dict(tol=1e-3, damping=0.5)  # absolute: the defaults scale with the UR5's reach (1.19)
    first = ik.solve(ur5, target, np.zeros(6), weights=(1.0, 0.5), **kw)
    before = len(COMPILES)
    results = [ik.solve(ur5, target, np.zeros(6), weights=w, **kw) for w in [(1.0, 0.3), (2.0, 1.0), (0.7, 0.1)]]
    assert len(COMPILES) == before, COMPILES[before:]
    assert len({r.iterations for r in [first, *results]}) > 1  # the weights did matter
    assert all(r.status == "converged" for r in results)


def _programs_during(run):
    """The names of the programs compiled while run() ran."""
    before = len(COMPILES)
    run()
    return COMPILES[before:]


def test_six_methods_on_a_new_arm_compile_one_loop_per_family():
    """The method is data (ikteach/_runtime/shared.py): the Jacobian methods share one compiled
    loop, CCD and FABRIK another; a second method, a new lambda or alpha compiles nothing."""
    arm, start = ik.planar_chain([0.6] * 5), np.full(5, 0.1)  # a shape no other test uses
    loops = [name for name in _programs_during(lambda: [
        ik.solve(arm, [1.0, 2.0], start, method=m, max_iter=40) for m in METHODS])
        if "traced_chunk" in name]
    assert len(loops) == 2, loops
    again = _programs_during(lambda: [
        ik.solve(arm, [1.5, 1.0], start, method=ik.DLS(damping=0.3)),
        ik.solve(arm, [1.5, 1.0], start, method=ik.Pinv(rcond=1e-3)),
        ik.solve(arm, [1.5, 1.0], start, method=ik.SDLS(gamma_max=0.5)),
        ik.track(arm, np.array([[1.0, 2.0], [1.1, 2.0]]), start, method="jt"),
        ik.track(arm, np.array([[1.0, 2.0], [1.1, 2.0]]), start, method="sdls")])
    assert [name for name in again if "traced_chunk" in name] == []
    assert len([name for name in again if "scan" in name]) == 1, again  # the first track only


def test_a_rest_gain_or_pose_weights_after_solves_without_them_compile_nothing():
    ur5 = ik.core.robots.ur5()
    start = np.full(6, 0.1)
    target = np.asarray(ik.fk_pose(ur5, np.full(6, 0.3)))
    ik.solve(ur5, target, start)
    ik.solve(ARM, [1.5, 1.0], START, rest_pose=np.zeros(3))
    assert _programs_during(lambda: [
        ik.solve(ur5, target, start, weights=(1.0, 0.5)),
        ik.solve(ur5, target, start, weights=(2, 1)),
        ik.solve(ARM, [1.5, 1.0], START, rest_pose=np.zeros(3), rest_gain=0.2),
        ik.solve(ARM, [1.2, 1.0], START, rest_pose=np.ones(3), rest_gain=1)]) == []


def test_batch_sizes_in_one_bucket_share_a_program():
    """solve_batch pads a batch to the next power of two (engine.bucket) and traces the count:
    9 to 16 targets run one program, 17 to 32 the next; the padding is never solved. A CPU's
    queue (1,024 in flight) pads past 1,024 rows to 8,192, 65,536, ...: the padding is never
    loaded into a slot, so a 128 x 128 map and a 256 x 256 one share a program."""
    from ikteach._runtime.engine import SLOTS, bucket

    assert [bucket(n) for n in (9, 16, 17, 100, 1000, 1025)] == [16, 16, 32, 128, 1024, 2048]
    queued = [bucket(n, queued=True) for n in (9, 1000, 1024, 1025, 8192, 16384, 65536, 65537)]
    assert queued == [16, 1024, 1024, 8192, 8192, 65536, 65536, 524288] and SLOTS == 1024
    arm, start = ik.planar_chain([0.7] * 4), np.full(4, 0.2)  # a shape no other test uses
    targets = np.random.default_rng(4).uniform(-2.0, 2.0, size=(32, 2))
    first = _programs_during(lambda: ik.solve_batch(arm, targets[:9], start, stall_tol=0))
    assert len([name for name in first if "queue" in name]) == 1, first
    rest = _programs_during(lambda: [ik.solve_batch(arm, targets[:n], start, stall_tol=0)
                                     for n in (10, 13, 16)])
    assert [name for name in rest if "queue" in name] == []
    whole = ik.solve_batch(arm, targets[:16], start, stall_tol=0)
    part = ik.solve_batch(arm, targets[:10], start, stall_tol=0)
    np.testing.assert_array_equal(part.theta, whole.theta[:10])
    np.testing.assert_array_equal(part.iterations, whole.iterations[:10])


def test_a_large_batch_of_another_size_reuses_the_queue():
    """Past the queue's 1,024 slots batches of 2,000 and 5,000 targets share one program (the
    8,192 bucket), and the results are the rows' own: as when each is solved alone."""
    arm, start = ik.planar_chain([0.8] * 4), np.full(4, 0.3)  # a shape no other test uses
    targets = np.random.default_rng(5).uniform(-3.0, 3.0, size=(5000, 2))
    first = _programs_during(lambda: ik.solve_batch(arm, targets[:2000], start, stall_tol=0))
    assert len([name for name in first if "queue" in name]) == 1, first
    whole = None

    def second():
        nonlocal whole
        whole = ik.solve_batch(arm, targets, start, stall_tol=0)
    assert [name for name in _programs_during(second) if "queue" in name] == []
    for k in (0, 1999, 4999):
        one = ik.solve(arm, targets[k], start, stall_tol=0)
        assert (one.status, one.iterations) == (whole.status[k], whole.iterations[k])
