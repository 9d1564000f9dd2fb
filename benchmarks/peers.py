"""ikteach next to two IK libraries people use in Python, on the same 7-joint arm and the same
random reachable position targets: success rate (final error below 1e-3) and time per target.

    pip install -e ".[bench]"        # ikpy and roboticstoolbox-python
    python benchmarks/peers.py [--targets 200]

The arm: 7 revolute joints about z, y, z, y, z, y, z (a KUKA-iiwa-like layout), links along z.
Targets are F(theta) for random theta, so each is reachable. Every solver starts from the same
theta0 and is asked for the position only. A peer that cannot be imported is reported, with
the reason, instead of timed.
"""
import argparse
import time

import numpy as np

import ikteach as ik

AXES = np.array([[0, 0, 1], [0, 1, 0]] * 3 + [[0, 0, 1]], dtype=float)
OFFSETS = np.array([[0, 0, z] for z in (0.34, 0.0, 0.4, 0.0, 0.4, 0.0, 0.126)])
SUCCESS = 1e-3


def ikteach_solver(arm, theta0):
    def solve_all(targets):
        res = ik.solve_batch(arm, targets, theta0, method="dls", damping=0.05, tol=1e-4, max_iter=500)
        return res.theta
    return solve_all


def ikpy_solver(theta0):
    from ikpy.chain import Chain
    from ikpy.link import OriginLink, URDFLink

    links = [OriginLink()]
    previous = np.zeros(3)
    for i in range(7):
        links.append(URDFLink(name=f"j{i}", origin_translation=previous, origin_orientation=[0, 0, 0],
                              rotation=AXES[i]))
        previous = OFFSETS[i]
    links.append(URDFLink(name="tip", origin_translation=previous, origin_orientation=[0, 0, 0],
                          joint_type="fixed"))
    chain = Chain(links, active_links_mask=[False] + [True] * 7 + [False])
    start = np.concatenate([[0.0], theta0, [0.0]])

    def solve_one(target):
        return chain.inverse_kinematics(target, initial_position=start)[1:8]
    fk = lambda q: chain.forward_kinematics(np.concatenate([[0.0], q, [0.0]]))[:3, 3]
    return solve_one, fk


def rtb_solver(theta0):
    import roboticstoolbox as rtb
    from roboticstoolbox import ET

    rot = {(0, 0, 1): ET.Rz, (0, 1, 0): ET.Ry}
    ets = ET.tz(0.0) * rot[tuple(AXES[0])]()
    for i in range(1, 7):
        ets = ets * ET.tz(OFFSETS[i - 1][2]) * rot[tuple(AXES[i])]()
    ets = ets * ET.tz(OFFSETS[6][2])
    robot = rtb.Robot(ets)
    mask = np.array([1, 1, 1, 0, 0, 0], dtype=float)

    def solve_one(target):
        T = np.eye(4)
        T[:3, 3] = target
        sol = robot.ik_LM(T, q0=theta0, mask=mask, ilimit=500, slimit=1, tol=1e-8)
        return np.asarray(sol[0])
    fk = lambda q: np.asarray(robot.fkine(q).A)[:3, 3]
    return solve_one, fk


def report(name, thetas, seconds, arm, targets):
    err = np.linalg.norm(np.stack([np.asarray(ik.fk(arm, q)) for q in thetas]) - targets, axis=1)
    ok = np.isfinite(err) & (err < SUCCESS)
    print(f"{name:<26} {ok.mean():>8.1%} {1e3 * seconds / len(targets):>12.3f} {np.median(err):>12.2e}")


def main(n_targets, seed=0):
    rng = np.random.default_rng(seed)
    arm = ik.serial_chain(AXES, OFFSETS)
    theta0 = np.full(7, 0.1)
    targets = np.stack([np.asarray(ik.fk(arm, q)) for q in rng.uniform(-2.0, 2.0, size=(n_targets, 7))])
    print(f"7-joint arm, {n_targets} random reachable targets, success = final error < {SUCCESS:g}")
    print(f"{'solver':<26} {'success':>8} {'ms / target':>12} {'median err':>12}")

    solve_all = ikteach_solver(arm, theta0)
    solve_all(targets), solve_all(targets[:1])  # compile for both shapes first (not timed)
    start = time.perf_counter()
    thetas = solve_all(targets)
    report("ikteach solve_batch (DLS)", thetas, time.perf_counter() - start, arm, targets)
    start = time.perf_counter()
    thetas = np.stack([solve_all(t[None])[0] for t in targets])
    report("ikteach, one at a time", thetas, time.perf_counter() - start, arm, targets)

    for name, make in (("ikpy", ikpy_solver), ("roboticstoolbox ik_LM", rtb_solver)):
        try:
            solve_one, fk = make(theta0)
        except Exception as exc:  # not installed, or failed to build: say why
            print(f"{name:<26} not run: {type(exc).__name__}: {exc}")
            continue
        q = rng.uniform(-1, 1, 7)
        gap = np.max(np.abs(fk(q) - np.asarray(ik.fk(arm, q))))
        if gap > 1e-9:
            print(f"{name:<26} not run: its model of the arm differs from ours by {gap:.2e}")
            continue
        start = time.perf_counter()
        thetas = np.stack([solve_one(t) for t in targets])
        report(name, thetas, time.perf_counter() - start, arm, targets)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--targets", type=int, default=200)
    main(ap.parse_args().targets)
