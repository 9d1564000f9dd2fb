"""`ikteach warm`: compile what the lectures compile, before anyone waits for it.

    ikteach warm [NOTEBOOK ...] [--cache DIR]

runs every lecture notebook top to bottom in a fresh kernel (outputs are thrown away, the
notebooks on disk are not touched), with JAX's persistent compilation cache in DIR (default:
the folder ik.notebook.setup() uses, ~/.cache/ikteach/jax). Afterwards a student's or a
lecturer's first run of a lecture loads its compiled solvers from that folder instead of
compiling them. The Binder image runs it at build time (binder/postBuild).

For each notebook it prints how many XLA programs the run needed and where they came from:
compiled now, or loaded from the cache. `count_programs` is the same run, returning the
numbers (benchmarks/compile_counts.py prints them as a table). The tests count the same way
on nbval's run of each lecture and hold it to its budget in BUDGETS (tests/lecture_budgets.py).
"""
import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from .notebook import CACHE_ENV, default_cache_dir

ROOT = Path(__file__).resolve().parents[2]

# Programs each lecture's Run All may need (compiled or loaded from the cache); a test fails
# above these. The counts are deterministic: docs/maintainers.md has the table.
BUDGETS = {
    "01_jacobian": 19,
    "02_jacobian_transpose": 29,
    "03_pseudoinverse": 25,
    "04_damped_least_squares": 49,
    "05_singularities_out_of_reach": 136,
    "06_pose_targets_3d": 53,
    "07_workspace_maps": 16,
    "08_methods_compared": 45,
    "09_characters": 27,
    "10_redundancy": 45,
}

# Run in the kernel before the notebook's first cell: count JAX's own compile events.
COUNT_CELL = """\
import jax.monitoring as _ikteach_monitoring
_ikteach_counts = {"programs": 0, "loaded": 0, "compile_s": 0.0, "trace_s": 0.0, "by_name": {}}
def _ikteach_duration(event, seconds, fun_name="?", **kwargs):
    if event.endswith("backend_compile_duration"):  # compiled, or loaded from the cache
        _ikteach_counts["programs"] += 1
        _ikteach_counts["compile_s"] += seconds
        named = _ikteach_counts["by_name"].setdefault(fun_name, [0, 0.0])
        named[0] += 1
        named[1] += seconds
    elif event.endswith(("jaxpr_trace_duration", "jaxpr_to_mlir_module_duration")):
        _ikteach_counts["trace_s"] += seconds
def _ikteach_event(event, **kwargs):
    if event == "/jax/compilation_cache/cache_hits":
        _ikteach_counts["loaded"] += 1
_ikteach_monitoring.register_event_duration_secs_listener(_ikteach_duration)
_ikteach_monitoring.register_event_listener(_ikteach_event)
"""
REPORT_CELL = "import json as _ikteach_json; print(_ikteach_json.dumps(_ikteach_counts))"


def lectures(root=ROOT):
    """The lecture notebooks, in teaching order."""
    return sorted((Path(root) / "notebooks").glob("[0-9][0-9]_*.ipynb"))


def count_programs(path, cache="off", timeout=900):
    """Run a notebook top to bottom in a fresh kernel with JAX's persistent cache in `cache`
    ("off": none). Returns {"programs", "compiled", "loaded", "compile_s", "trace_s", "wall_s",
    "by_name"}: the XLA programs the run needed, how many of them were compiled now and how
    many loaded from the cache, seconds spent compiling or loading them, seconds of tracing
    and lowering (never cached), the run's wall time (kernel start included), and per
    function name [programs, seconds]."""
    import nbformat
    from nbclient import NotebookClient

    path = Path(path)
    nb = nbformat.read(path, as_version=4)
    nb.cells.insert(0, nbformat.v4.new_code_cell(COUNT_CELL))
    nb.cells.append(nbformat.v4.new_code_cell(REPORT_CELL))
    env = dict(os.environ, **{CACHE_ENV: str(cache)})
    start = time.perf_counter()
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3",
                            resources={"metadata": {"path": str(path.parent)}})
    saved = os.environ.copy()
    os.environ.update(env)  # the kernel inherits this process's environment
    try:
        client.execute(stderr=subprocess.DEVNULL)
    finally:
        os.environ.clear()
        os.environ.update(saved)
    wall = time.perf_counter() - start
    counts = read_counts("".join(out.get("text", "") for out in nb.cells[-1].outputs))
    counts["wall_s"] = wall
    return counts


def read_counts(printed):
    """The counts REPORT_CELL printed (also read by tests/lecture_budgets.py, on nbval's run)."""
    counts = json.loads(printed.strip().splitlines()[-1])
    counts["compiled"] = counts["programs"] - counts["loaded"]
    return counts


def parser():
    p = argparse.ArgumentParser(prog="ikteach warm", description=__doc__.split("\n")[0])
    p.add_argument("notebooks", nargs="*", type=Path,
                   help="notebooks to run (default: every lecture in notebooks/)")
    p.add_argument("--cache", default=None,
                   help=f"the compilation cache folder (default: ${CACHE_ENV}, else "
                        "~/.cache/ikteach/jax, the folder the notebooks use)")
    return p


def main(argv=None):
    args = parser().parse_args(argv)
    cache = args.cache or default_cache_dir()
    if cache is None:
        print(f"ikteach warm: the compilation cache is off (${CACHE_ENV}=off): nothing to warm",
              file=sys.stderr)
        return 2
    paths = args.notebooks or lectures(Path.cwd()) or lectures()
    if not paths:
        print("ikteach warm: no lecture notebooks found (run it in the course's folder, or "
              "name the notebooks)", file=sys.stderr)
        return 2
    print(f"warming {cache} with {len(paths)} notebooks")
    total = 0.0
    for path in paths:
        counts = count_programs(path, cache)
        total += counts["wall_s"]
        print(f"  {path.name:<36} {counts['programs']:>3} programs "
              f"({counts['compiled']} compiled, {counts['loaded']} already warm) "
              f"{counts['wall_s']:6.1f} s", flush=True)
    print(f"done in {total:.0f} s: the first run of each lecture now loads its compiled code")
    return 0


if __name__ == "__main__":
    sys.exit(main())
