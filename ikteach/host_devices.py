"""One JAX CPU device per core, so that ik.solve_batch can split a batch over the cores.

JAX gives the host a single CPU device unless told otherwise before it starts its backends,
and one device runs a solve_batch loop on one core. Imported before JAX has started, ikteach
asks for one CPU device per available core (at most MAX_DEVICES). Programs that are not split
run on the first device, as before. IKTEACH_CPU_DEVICES=1 keeps one device, a number asks for
that many; a count already chosen (jax_num_cpu_devices, or the XLA flag) is left as it is.
"""
import os
import sys

DEVICES_ENV = "IKTEACH_CPU_DEVICES"
XLA_FLAG = "--xla_force_host_platform_device_count"
MAX_DEVICES = 8


def available_cores():
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def wanted(env=None, cores=None):
    """How many CPU devices to ask for: $IKTEACH_CPU_DEVICES, else the cores (at most 8)."""
    env = os.environ if env is None else env
    value = env.get(DEVICES_ENV, "").strip()
    if value:
        try:
            count = int(value)
        except ValueError:
            raise ValueError(f"{DEVICES_ENV}: expected a whole number of CPU devices, "
                             f"got {value!r}") from None
        if count < 1:
            raise ValueError(f"{DEVICES_ENV}: expected at least 1 CPU device, got {count}")
        return count
    return max(1, min(available_cores() if cores is None else cores, MAX_DEVICES))


def request(jax):
    """Ask JAX for wanted() CPU devices if it is still free to give them; returns the count
    asked for, or None (too late, already chosen, or one device)."""
    xb = sys.modules.get("jax._src.xla_bridge")
    if xb is not None and getattr(xb, "_backends", None):
        return None  # backends started: the device count is fixed
    if XLA_FLAG in os.environ.get("XLA_FLAGS", "") or getattr(jax.config, "jax_num_cpu_devices", -1) != -1:
        return None
    count = wanted()
    if count == 1:
        return None
    try:
        jax.config.update("jax_num_cpu_devices", count)
    except (AttributeError, ValueError, RuntimeError):  # an older jax: the XLA flag
        os.environ["XLA_FLAGS"] = f"{os.environ.get('XLA_FLAGS', '')} {XLA_FLAG}={count}".strip()
    return count
