"""JAX CPU devices for the cores, so that ik.solve_batch can split a large batch over them.

JAX gives the host one CPU device unless told otherwise before its backends start, and one
device runs a solve_batch loop on one core. This is an opt-in, never a side effect of
`import ikteach`: ik.notebook.setup(cpu_devices="cores") asks for it (the course notebooks
do), as does a script that calls use_cores() before its first JAX operation. Each target gets
the same iterates either way (tests/test_devices.py).

"cores" means one device per TWO cores (at most MAX_DEVICES): with as many devices as cores,
a split batch whose step makes sizeable LAPACK calls (pose targets, trees, a 12-joint chain's
SVD) waited forever in XLA's CPU runtime (2 devices on 2 cores, jaxlib 0.10.2: 2,048 iiwa
poses, 2,048 double-Y targets, 8,192 12-joint pinv targets; planar and small steps split
fine): every device ran on one of the cores' threads and the LAPACK call waited for a free one.
With a thread to spare per device that wait ends. So a 2-core machine keeps one device; ask
for more with setup(cpu_devices=N) or IKTEACH_CPU_DEVICES=N (benchmarks/sweep.py asks for
one per core: its planar DLS step has no LAPACK call).
Off: setup(cpu_devices=1), or IKTEACH_CPU_DEVICES=1.
"""
import os

DEVICES_ENV = "IKTEACH_CPU_DEVICES"
MAX_DEVICES = 8


def available_cores():
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def wanted(choice="cores", env=None, cores=None):
    """How many CPU devices a choice means: a whole number, or "cores" (one per two cores,
    at most MAX_DEVICES: module doc); $IKTEACH_CPU_DEVICES, when set, wins."""
    env = os.environ if env is None else env
    value = env.get(DEVICES_ENV, "").strip() or choice
    name = DEVICES_ENV if env.get(DEVICES_ENV, "").strip() else "cpu_devices"
    if value == "cores":
        return max(1, min((available_cores() if cores is None else cores) // 2, MAX_DEVICES))
    try:
        count = int(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a whole number of CPU devices or 'cores', "
                         f"got {value!r}") from None
    if count < 1 or isinstance(value, bool):
        raise ValueError(f"{name}: expected at least 1 CPU device, got {value!r}")
    return count


def use_cores(choice="cores"):
    """Ask JAX for wanted(choice) CPU devices through its public config. Returns the count now
    in force, or None when JAX's backends have started (the count is fixed then) or a count was
    chosen elsewhere (jax_num_cpu_devices, or --xla_force_host_platform_device_count)."""
    import jax

    count = wanted(choice)
    if "xla_force_host_platform_device_count" in os.environ.get("XLA_FLAGS", ""):
        return None
    current = jax.config.jax_num_cpu_devices
    if current not in (-1, count):
        return None
    try:
        jax.config.update("jax_num_cpu_devices", count)
    except RuntimeError:  # "should be updated before backends are initialized"
        return None
    return count
