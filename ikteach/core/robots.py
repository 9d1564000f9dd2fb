"""Built-in example arms, from published kinematic parameters (numbers in the code).

A Chain has no fixed link rotations: at theta = 0 every frame is aligned with the world,
so an arm is its joint axes and link offsets in the home (zero) configuration, as in the
product-of-exponentials form T(theta) = exp([S_1] theta_1) ... exp([S_n] theta_n) M.
Published Denavit-Hartenberg tables are converted to that form by walking the DH frames
at theta = 0: joint i turns about z of DH frame i-1, and sits at that frame's origin.
The DH flange frame at home, M = dh_home_rotation(...), is the rotation the Chain's
end frame is measured against: R_DH(theta) = R_chain(theta) M.
"""
import numpy as np

from .chain import serial_chain


def dh_transform(d, a, alpha, theta):
    """Standard DH link transform A_i = Rot_z(theta) Trans_z(d) Trans_x(a) Rot_x(alpha)."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([
        [ct, -st * ca, st * sa, a * ct],
        [st, ct * ca, -ct * sa, a * st],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ])


def dh_fk(d, a, alpha, theta):
    """Flange pose by the DH product T = A_1 A_2 ... A_n (numpy, for checking the conversion)."""
    T = np.eye(4)
    for di, ai, al, th in zip(d, a, alpha, theta):
        T = T @ dh_transform(di, ai, al, th)
    return T


def chain_from_dh(d, a, alpha):
    """A serial_chain equal to a standard DH table (all joints revolute, zero offsets).

    At theta = 0 the DH frames F_0 .. F_n give joint i's world axis z_{i-1} and its
    position o_{i-1}; link offsets are o_i - o_{i-1} (o_n the flange).
    """
    T = np.eye(4)
    axes, origins = [], [T[:3, 3].copy()]
    for di, ai, al in zip(d, a, alpha):
        axes.append(T[:3, 2].copy())
        T = T @ dh_transform(di, ai, al, 0.0)
        origins.append(T[:3, 3].copy())
    origins = np.array(origins)
    return serial_chain(np.array(axes), np.diff(origins, axis=0))


def dh_home_rotation(d, a, alpha):
    """The DH flange rotation at theta = 0 (M's rotation part)."""
    return dh_fk(d, a, alpha, np.zeros(len(d)))[:3, :3]


# Universal Robots UR5, 6 joints. Standard DH parameters published by Universal Robots
# ("DH parameters for calculations of kinematics and dynamics", UR support article), in metres:
#   d     = [0.089159, 0, 0, 0.10915, 0.09465, 0.0823]
#   a     = [0, -0.425, -0.39225, 0, 0, 0]
#   alpha = [pi/2, 0, 0, pi/2, -pi/2, 0]
UR5_DH = dict(
    d=np.array([0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823]),
    a=np.array([0.0, -0.425, -0.39225, 0.0, 0.0, 0.0]),
    alpha=np.array([np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0]),
)

# KUKA LBR iiwa 14 R820, 7 joints (redundant). Standard DH parameters from the KUKA data
# sheet link lengths (base-shoulder 0.360 m, shoulder-elbow 0.420 m, elbow-wrist 0.400 m,
# wrist-flange 0.126 m), as used e.g. in the iiwa_stack URDF:
#   d     = [0.36, 0, 0.42, 0, 0.4, 0, 0.126]
#   a     = [0, 0, 0, 0, 0, 0, 0]
#   alpha = [-pi/2, pi/2, pi/2, -pi/2, -pi/2, pi/2, 0]
IIWA14_DH = dict(
    d=np.array([0.36, 0.0, 0.42, 0.0, 0.4, 0.0, 0.126]),
    a=np.zeros(7),
    alpha=np.array([-np.pi / 2, np.pi / 2, np.pi / 2, -np.pi / 2, -np.pi / 2, np.pi / 2, 0.0]),
)


def ur5():
    """A 6-joint industrial arm modelled on the Universal Robots UR5 (DH table UR5_DH)."""
    return chain_from_dh(**UR5_DH)


def iiwa14():
    """A 7-joint redundant arm modelled on the KUKA LBR iiwa 14 R820 (DH table IIWA14_DH)."""
    return chain_from_dh(**IIWA14_DH)


ROBOTS = {"ur5": (ur5, UR5_DH), "iiwa14": (iiwa14, IIWA14_DH)}
