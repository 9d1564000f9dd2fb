"""pyvista scenes: off-screen rendering, image regression against a committed reference."""
import numpy as np
import pytest

import ikteach as ik
from ikteach import scene

from render_reference import SCENE_PNG, SCENE_THETA, read_png, scene_image, ssim

# Measured when the reference was made: the same render scores 1.0; joint 3 moved by 0.1 rad
# 0.84, joint 6 by 0.2 rad 0.96, the link colour blue -> green 0.992, joints orange -> red 0.987.
SCENE_SSIM = 0.995


@pytest.fixture(scope="module")
def reference():
    return read_png(SCENE_PNG)


def test_scene_matches_the_reference_image(reference):
    image = scene_image()
    assert image.shape == reference.shape
    assert ssim(reference, image, crop_to=reference) > SCENE_SSIM


def test_moving_a_link_fails_the_comparison(reference):
    theta = SCENE_THETA.copy()
    theta[2] += 0.1
    assert ssim(reference, scene_image(theta), crop_to=reference) < SCENE_SSIM


def test_changing_a_colour_fails_the_comparison(reference):
    assert ssim(reference, scene_image(colors={"link": "#55a868"}), crop_to=reference) < SCENE_SSIM


def test_arm_meshes_sit_on_the_joints():
    arm = ik.iiwa14()
    theta = np.linspace(-0.5, 0.7, 7)
    positions, axes, T = scene.frames(arm, theta)
    parts = scene.arm_meshes(arm, theta)
    # base, a tube per non-zero link (the iiwa's joints 1-2, 3-4, 5-6 share a point),
    # 7 joint cylinders, the end-effector sphere
    links = int(np.sum(np.linalg.norm(np.diff(positions, axis=0), axis=1) > 1e-9))
    assert links == 4
    assert len(parts) == 1 + links + 7 + 1
    for (mesh, _), p in zip(parts[1 + links:1 + links + 7], positions[:-1]):
        np.testing.assert_allclose(mesh.center, p, atol=1e-6)
    np.testing.assert_allclose(T[:3, 3], np.asarray(ik.fk(arm, theta)), atol=1e-12)


def test_solve_gif_writes_frames(tmp_path):
    arm = ik.ur5()
    target = np.asarray(ik.fk_pose(arm, SCENE_THETA + 0.2))
    res = ik.solve(arm, target, SCENE_THETA, tol=1e-6, damping=0.05, max_iter=100)
    path = scene.solve_gif(arm, res.trace.theta, tmp_path / "solve.gif", target=target, frames_max=5)
    from PIL import Image

    with Image.open(path) as gif:
        assert gif.n_frames == min(5, len(res.trace.theta))
        assert gif.size == (320, 240)
