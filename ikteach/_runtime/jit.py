"""jax.jit for the course's programs (the whole loops, and the small functions lectures call on
their own: quick_jit), on JAX's public API, with three choices that buy speed and can each be
turned off without changing a result.

1. XLA's classic CPU emitters (`compiler_options`, a public argument of jax.jit). The newer
   "fusion emitters" build one LLVM module per fused kernel; for the course's loops (a few
   dozen kernels on a handful of numbers) the classic ones compile the same program in about
   0.55-0.75 of the time and run it as fast (first solve of a 3-link arm: jt 500 -> 280 ms;
   benchmarks/latency.py, "first" column). Tried once, on the first call, with a one-line
   program: a jaxlib that does not know the option gets plain jax.jit.
   IKTEACH_XLA_OPTIONS=off turns it off (tests/test_jit.py: same statuses, iterations, angles).
   The small functions that lectures also call on their own, a few times per shape (fk, J,
   one method step: `quick_jit`) compile with them too: fk of a 3-link arm in 85 ms instead of
   145 ms, J in 110 ms instead of 225 ms. Where a loop calls them, they are inlined into its
   program. (Not light, as in 2: 65 ms for fk, but its last bits would differ from the
   loop's, which tests compare.)

2. Light programs: a program that runs once on a row or two (the stall classifier after a
   solve) is compiled at XLA's lowest backend optimisation level (`xla_backend_optimization_level`
   0, also a compiler option). It compiles in about half the time and runs about three times
   slower, milliseconds for one row; the classifier's 1,024-row program for a batch is
   compiled in full. Tried alike (a jaxlib that does not take it compiles in full), and off
   with IKTEACH_XLA_OPTIONS=off.

3. A bound on what one process keeps compiled. Each whole-loop program holds about 140 memory
   mappings and 5-8 MB; a kernel used all lecture long would otherwise reach the system's limit
   on mappings (vm.max_map_count, 65530 on Debian) and die. When MAX_PROGRAMS programs have
   been compiled or loaded since the last clear (counted by JAX's public compile events, which
   cost nothing per call; a load from the persistent cache counts too), JAX's caches are
   cleared with its public jax.clear_caches(): the programs still in use compile again, or
   load from JAX's persistent compilation cache when ik.notebook.setup() turned it on
   (benchmarks/many_programs.py shows mappings and memory levelling off). MAX_PROGRAMS = 256
   is about 27,000 mappings, well under the limit, and above every lecture's budget
   (ikteach/course/warm.py: BUDGETS; tests/lecture_budgets.py). A lower bound does not buy
   memory where the cache is on: 10,000 varied solves held 1,554 MB with 256 and 1,575 MB with
   144 (the reloaded programs take the freed room and more), and took 40 % longer.
   IKTEACH_MAX_PROGRAMS=0 turns it off.
"""
import functools
import os

import jax

OPTIONS_ENV = "IKTEACH_XLA_OPTIONS"
BOUND_ENV = "IKTEACH_MAX_PROGRAMS"
FAST_COMPILE = {"xla_cpu_use_fusion_emitters": False}
LIGHT_COMPILE = {"xla_backend_optimization_level": 0}
MAX_PROGRAMS = 256


def supported(options):
    """Does this jaxlib compile with these options (unknown names raise, they do not abort)?"""
    try:
        jax.jit(lambda x: x, compiler_options=options).lower(0.0).compile()
        return True
    except Exception:  # TypeError (no compiler_options), XLA's "No such compile option", ...
        return False


@functools.lru_cache(maxsize=None)
def _taken():
    """Which of FAST_COMPILE and LIGHT_COMPILE this jaxlib takes: both tried in one program,
    each alone only when that fails."""
    if supported({**FAST_COMPILE, **LIGHT_COMPILE}):
        return True, True
    return supported(FAST_COMPILE), supported(LIGHT_COMPILE)


def compiler_options(light=False):
    """FAST_COMPILE (and LIGHT_COMPILE when light), each where this jaxlib takes it; None when
    none is taken or IKTEACH_XLA_OPTIONS is "off"."""
    if os.environ.get(OPTIONS_ENV, "").strip().lower() in ("off", "0", "false", "no"):
        return None
    fast, lite = _taken()
    options = {**(FAST_COMPILE if fast else {}), **(LIGHT_COMPILE if light and lite else {})}
    return options or None


def max_programs():
    """MAX_PROGRAMS, or $IKTEACH_MAX_PROGRAMS (0: no bound)."""
    value = os.environ.get(BOUND_ENV, "").strip()
    if not value:
        return MAX_PROGRAMS
    try:
        return max(0, int(value))
    except ValueError:
        raise ValueError(f"{BOUND_ENV}: expected a whole number of programs, got {value!r}") from None


compiled = [0]  # programs JAX compiled since the last clear (all of them: loops and small ops)
clears = [0]  # how many times the bound cleared JAX's caches (read by tests and benchmarks)


def _count(event, duration, **kwargs):
    if event.endswith("backend_compile_duration"):
        compiled[0] += 1


jax.monitoring.register_event_duration_secs_listener(_count)  # public: JAX's own compile events


def keep_within_bound():
    """Past max_programs() compiled programs, clear JAX's caches and start counting again.
    Called before each whole-loop program runs (never while JAX is compiling)."""
    bound = max_programs()
    if bound and compiled[0] >= bound:
        jax.clear_caches()
        compiled[0] = 0
        clears[0] += 1


def jax_jit(fun, static_argnames, options):
    """jax.jit(fun) with these compiler options (None: none); static_argnames a name or names."""
    names = (static_argnames,) if isinstance(static_argnames, str) else tuple(static_argnames)
    kwargs = {"compiler_options": options} if options else {}
    return jax.jit(fun, static_argnames=names, **kwargs)


class Program:
    """A jitted whole-loop program, run within the bound on compiled programs."""

    def __init__(self, fun, static_argnames=(), fast_compile=True, light=False):
        self.fun, self.static_argnames, self.fast_compile = fun, static_argnames, fast_compile
        self.light = light
        self._jitted = None
        functools.update_wrapper(self, fun)

    def jitted(self):
        if self._jitted is None:
            options = compiler_options(self.light) if self.fast_compile else None
            self._jitted = jax_jit(self.fun, self.static_argnames, options)
        return self._jitted

    def clear_cache(self):
        """Drop this function's compiled programs (jax.jit's own clear_cache)."""
        if self._jitted is not None:
            self._jitted.clear_cache()

    def __call__(self, *args, **kwargs):
        keep_within_bound()
        return self.jitted()(*args, **kwargs)


def jit(fun=None, fast_compile=True, static_argnames=(), light=False):
    """Program(fun): jax.jit with compiler_options(light) and the bound above; as a decorator
    with or without arguments (`@jit`, `@partial(jit, static_argnames=...)`). Static arguments
    are named in static_argnames. fast_compile=False compiles exactly as jax.jit does; light:
    a program that runs briefly (module doc, 2)."""
    if fun is None:
        return functools.partial(jit, fast_compile=fast_compile, static_argnames=static_argnames,
                                 light=light)
    return Program(fun, static_argnames, fast_compile, light)


class QuickProgram:
    """jax.jit of a small function: called on its own, compiled with compiler_options();
    called inside another program's trace (JAX takes compiler options only at the top level),
    a plain jax.jit inlined there. Outside the bound on programs (it may run while a loop's
    program is traced)."""

    def __init__(self, fun, static_argnames=()):
        self.fun, self.static_argnames, self._jitted = fun, static_argnames, {}
        functools.update_wrapper(self, fun)

    def jitted(self, quick):
        if quick not in self._jitted:
            options = compiler_options() if quick else None
            self._jitted[quick] = jax_jit(self.fun, self.static_argnames, options)
        return self._jitted[quick]

    def __call__(self, *args, **kwargs):
        if any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves((args, kwargs))):
            return self.jitted(False)(*args, **kwargs)  # inside a trace
        try:
            return self.jitted(True)(*args, **kwargs)
        except ValueError:  # a trace of constants only (no options there), or fun's own error
            return self.jitted(False)(*args, **kwargs)  # which this raises again


def quick_jit(fun=None, static_argnames=()):
    """jax.jit for a small function that lectures also call on their own, a few times per
    shape (fk, J, one step): compiled with the classic emitters (module doc, 1).
    `@quick_jit` or `@partial(quick_jit, static_argnames=...)`."""
    if fun is None:
        return functools.partial(quick_jit, static_argnames=static_argnames)
    return QuickProgram(fun, static_argnames)
