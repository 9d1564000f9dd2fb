"""A 10-joint planar chain (links of length 1), 20 random reachable and 20 random unreachable
targets: iterations and time per solve for each method.

The same kind of comparison as Aristidou & Lasenby's, "FABRIK: a fast, iterative solver for the
inverse kinematics problem" (2011), but not a reproduction of their table: their chains, targets,
tolerance and implementations differ, and no number of theirs is quoted or compared here.

    python benchmarks/fabrik_table.py [--runs 20] [--tol 0.01]
"""
import argparse
import time

import numpy as np

import ikteach as ik

METHODS = ["fabrik", "ccd", "jt", "pinv", "dls", "sdls"]
LABELS = {"fabrik": "FABRIK", "ccd": "CCD", "jt": "Jacobian transpose", "pinv": "Pseudoinverse (SVD)",
          "dls": "DLS (lambda 0.5)", "sdls": "SDLS"}


def problems(runs, seed=0, n=10):
    """Reachable targets: F of random angles. Unreachable: 1.1 to 2 times the reach, any direction."""
    rng = np.random.default_rng(seed)
    arm = ik.planar_chain(np.ones(n))
    reachable = np.stack([np.asarray(ik.fk(arm, rng.uniform(-np.pi, np.pi, n))) for _ in range(runs)])
    phi = rng.uniform(-np.pi, np.pi, runs)
    far = n * rng.uniform(1.1, 2.0, runs)
    unreachable = np.stack([far * np.cos(phi), far * np.sin(phi)], axis=1)
    return arm, np.full(n, 0.1), {"reachable": reachable, "unreachable": unreachable}


def measure(arm, theta0, targets, method, tol, max_iter, repeat=1):
    """Per target: status and iterations (ik.solve) and the best of `repeat` wall times of the
    compiled loop alone (ik.solve_batch on that one target, compiled once beforehand)."""
    kw = dict(method=method, tol=tol, max_iter=max_iter)
    ik.solve_batch(arm, targets[:1], theta0, **kw)  # compile
    rows = []
    for t in targets:
        res = ik.solve(arm, t, theta0, **kw)
        best = np.inf
        for _ in range(repeat):
            start = time.perf_counter()
            ik.solve_batch(arm, t[None], theta0, **kw)
            best = min(best, time.perf_counter() - start)
        rows.append((res.status, res.iterations, best))
    return rows


def table(runs=20, tol=0.01, max_iter=1000, repeat=1, methods=METHODS):
    arm, theta0, sets = problems(runs)
    out = []
    for kind, targets in sets.items():
        for m in methods:
            rows = measure(arm, theta0, targets, m, tol, max_iter, repeat)
            status = [r[0] for r in rows]
            its = np.array([r[1] for r in rows], dtype=float)
            secs = np.array([r[2] for r in rows])
            ok = "converged" if kind == "reachable" else "stalled"
            out.append(dict(kind=kind, method=m, ok=sum(s == ok for s in status), runs=len(rows),
                            iterations=its.mean(), ms=1e3 * secs.mean(),
                            us_per_iter=1e6 * secs.sum() / max(its.sum(), 1)))
    return out


def print_table(rows, timings=True):
    head = f"{'targets':<12} {'method':<20} {'ended ok':>8} {'mean iters':>10}"
    if timings:
        head += f" {'ms / solve':>10} {'us / iter':>9}"
    print(head)
    for r in rows:
        line = (f"{r['kind']:<12} {LABELS[r['method']]:<20} {r['ok']:>4}/{r['runs']:<3} "
                f"{r['iterations']:>10.1f}")
        if timings:
            line += f" {r['ms']:>10.2f} {r['us_per_iter']:>9.1f}"
        print(line)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--tol", type=float, default=0.01)
    ap.add_argument("--max-iter", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    print(f"10-joint planar chain, {a.runs} runs, tol {a.tol}, max_iter {a.max_iter}; "
          "'ended ok' = converged (reachable) or stalled (unreachable).")
    print("Time = wall time of the jit-compiled loop for one target (ik.solve_batch with one row), "
          f"best of {a.repeat}, CPU.\n")
    print_table(table(a.runs, a.tol, a.max_iter, a.repeat))
