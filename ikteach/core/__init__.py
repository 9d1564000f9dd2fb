"""The IK core a student reads: chains and trees, forward kinematics, the Jacobian, the update
rules (jt, pinv, dls, sdls, ccd, fabrik), clamps, stop rules, tasks, priorities, joint limits,
the solve loop, batches, tracking and workspace sweeps. Imports only numpy and JAX (and the
private ikteach._runtime for jit)."""
from .._lazy import submodules  # noqa: E402

__getattr__ = submodules(__name__, globals())  # ik.core.<module>: imported on first use
