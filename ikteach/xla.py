"""jax.jit with the compiler options our programs compile fastest with.

XLA's CPU backend turns every fused kernel into its own small LLVM module. With its newer
"fusion emitters" each of those modules costs more to build; for the course's programs (loops
over a few dozen kernels on a handful of numbers) the classic emitters compile the same
program in about 0.55-0.75 of the time and run it as fast (first solve of a 3-link arm, this
machine: jt 500 -> 280 ms, pinv 650 -> 380 ms; benchmarks/latency.py).

JAX takes compiler options only on a top-level jit, so they go on the programs a call
compiles as a whole (the solve, batch, tracking and clip loops, the singularity map); the
small functions they call (kinematics, steps) stay plain jax.jit. The option is tried once,
on a one-line program, when ikteach is imported: a jaxlib that does not know it gets plain
jax.jit. IKTEACH_XLA_OPTIONS=off turns it off.
"""
import functools
import os

import jax

from . import program_store

FAST_COMPILE = {"xla_cpu_use_fusion_emitters": False}
OPTIONS_ENV = "IKTEACH_XLA_OPTIONS"


def supported(options):
    """Does this jaxlib compile with these options (unknown names raise, they do not abort)?"""
    try:
        jax.jit(lambda x: x, compiler_options=options).lower(0.0).compile()
        return True
    except Exception:  # TypeError (no compiler_options), XLA's "No such compile option", ...
        return False


def _chosen():
    if os.environ.get(OPTIONS_ENV, "").strip().lower() in ("off", "0", "false", "no"):
        return None
    return dict(FAST_COMPILE) if supported(FAST_COMPILE) else None


COMPILER_OPTIONS = _chosen()


def jit(fun=None, fast_compile=True, **kwargs):
    """jax.jit(fun, **kwargs) with COMPILER_OPTIONS; as a decorator, with or without arguments
    (`@jit`, `@partial(jit, static_argnames=...)`). Its executables are also kept whole in the
    program store when compilation_cache() opened one (ikteach/program_store.py).
    fast_compile=False leaves out COMPILER_OPTIONS: compiled exactly as jax.jit does, for
    functions whose results must stay equal to the bit to what they were (still stored)."""
    if fun is None:
        return functools.partial(jit, fast_compile=fast_compile, **kwargs)
    if COMPILER_OPTIONS and fast_compile:
        kwargs.setdefault("compiler_options", COMPILER_OPTIONS)
    jitted = jax.jit(fun, **kwargs)
    if "static_argnums" in kwargs:
        return jitted
    return program_store.StoredProgram(fun, jitted, kwargs.get("static_argnames", ()))
