"""One CPU device per core, asked for by ik.notebook.setup() (never by import), and solve_batch
split over them: the same iterates to the bit."""
import os
import subprocess
import sys
import textwrap

import pytest

from ikteach._runtime import devices

SPLIT_CHECK = textwrap.dedent("""
    import numpy as np, jax, ikteach as ik
    from ikteach._runtime import engine as batch
    ik.notebook.setup(cpu_devices=3)
    ik.notebook.compilation_cache()  # the tests' folder ($IKTEACH_JAX_CACHE), as in conftest
    assert len(jax.devices()) == 3, jax.devices()
    rng = np.random.default_rng(1)
    arm, ur5 = ik.planar_chain([1.0, 0.8, 0.5]), ik.core.robots.ur5()
    planar = rng.uniform(-2.6, 2.6, size=(1001, 2))   # 1001 = 3 x 333 + 2: padded shares
    poses = np.stack([np.asarray(ik.fk_pose(ur5, q)) for q in rng.uniform(-1, 1, size=(40, 6))])
    cases = [(arm, planar, np.array([0.3, 0.2, 0.1]), dict(method="dls", damping=0.3)),
             (arm, planar, rng.uniform(-1, 1, size=(1001, 3)), dict(method="jt", max_iter=300)),
             (arm, planar, np.zeros(3), dict(method="ccd")),
             (arm, planar, np.zeros(3), dict(method=lambda J, e: ik.dls_step(J, e, 0.2))),
             (ur5, poses, np.zeros(6), dict(method="pinv", tol=1e-6, max_iter=100))]
    for arm_, targets, start, kw in cases:
        batch.SPLIT_FROM = 10**9
        whole = ik.solve_batch(arm_, targets, start, **kw)
        batch.SPLIT_FROM = 8
        assert batch.split_devices(len(targets)) is not None
        split = ik.solve_batch(arm_, targets, start, **kw)
        for field in ("theta", "status", "iterations"):
            assert np.array_equal(getattr(whole, field), getattr(split, field)), (kw, field)
        # |e| of a pose sums six parts; its last bit moves with the batch width (as it does
        # between any two batch sizes on one device): equal for planar targets, close for poses
        if targets.ndim == 2:
            assert np.array_equal(whole.error, split.error), kw
        np.testing.assert_allclose(split.error, whole.error, rtol=1e-12, atol=1e-300)
    print("split ok", len(set(whole.status)), int(whole.iterations.sum()))
""")


def test_a_batch_split_over_devices_gives_the_same_answers_to_the_bit():
    env = dict(os.environ, IKTEACH_CPU_DEVICES="3")
    env.pop("XLA_FLAGS", None)
    out = subprocess.run([sys.executable, "-c", SPLIT_CHECK], env=env, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-3000:]
    assert "split ok" in out.stdout


def _device_count(code, **env_extra):
    env = dict(os.environ, **env_extra)
    env.pop("XLA_FLAGS", None)
    env.pop(devices.DEVICES_ENV, None) if devices.DEVICES_ENV not in env_extra else None
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout.split()[-1]


def test_import_leaves_the_device_count_alone():
    assert _device_count("import jax, ikteach; print(len(jax.devices()))") == "1"


def test_setup_asks_for_one_device_per_core_and_one_when_told():
    code = "import jax, ikteach as ik; ik.notebook.setup(cpu_devices={}); print(len(jax.devices()))"
    assert _device_count(code.format("'cores'")) == str(devices.wanted("cores", env={}))
    assert _device_count(code.format(1)) == "1"
    assert _device_count(code.format("'cores'"), IKTEACH_CPU_DEVICES="1") == "1"


def test_wanted_counts_the_cores_up_to_the_cap():
    assert devices.wanted("cores", {}, cores=2) == 1  # one per two cores (devices.py)
    assert devices.wanted("cores", {}, cores=4) == 2
    assert devices.wanted("cores", {}, cores=64) == devices.MAX_DEVICES
    assert devices.wanted(3, {}) == 3
    assert devices.wanted("cores", {devices.DEVICES_ENV: " 5 "}, cores=2) == 5


@pytest.mark.parametrize("value", ["two", "0", "-1", "1.5"])
def test_a_bad_device_count_names_the_variable(value):
    with pytest.raises(ValueError, match=devices.DEVICES_ENV):
        devices.wanted("cores", {devices.DEVICES_ENV: value})
    with pytest.raises(ValueError, match="cpu_devices"):
        devices.wanted(value, {})


def test_too_late_once_jax_has_started():
    import jax

    jax.devices()
    assert devices.use_cores(len(jax.devices()) + 1) is None


POSE_BATCH = textwrap.dedent("""
    import numpy as np, jax, ikteach as ik
    rng = ik.notebook.setup()  # the course's devices: one per two cores
    arm = ik.core.robots.iiwa14()
    poses = np.stack([np.asarray(ik.fk_pose(arm, q)) for q in rng.uniform(-1, 1, size=(32, 7))])
    batch = ik.solve_batch(arm, poses[rng.integers(0, 32, 2048)], np.zeros(7), max_iter=5)
    print("done", len(jax.devices()), batch.counts()["max_iter"])
""")


def test_a_large_pose_batch_finishes_on_the_course_s_devices():
    """2,048 pose targets (a sizeable LAPACK call per step) waited forever when split over as
    many CPU devices as cores; setup() now keeps a core to spare per device (devices.py)."""
    env = dict(os.environ)
    env.pop("XLA_FLAGS", None)
    env.pop(devices.DEVICES_ENV, None)
    out = subprocess.run([sys.executable, "-c", POSE_BATCH], env=env, capture_output=True,
                         text=True, timeout=240)
    assert out.returncode == 0, out.stderr[-3000:]
    last = out.stdout.splitlines()[-1].split()
    assert last[0] == "done" and last[-1] == "2048", out.stdout
