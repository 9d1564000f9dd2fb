"""The figures behind the image-regression tests (tests/test_scene.py, tests/test_workspace.py).

Regenerate the committed references, after a deliberate change to the drawing, with
    .venv/bin/python tests/render_reference.py
"""
import os
from pathlib import Path

import numpy as np

os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")

import ikteach as ik  # noqa: E402

REFERENCE = Path(__file__).resolve().parent / "reference"
SCENE_PNG = REFERENCE / "scene_ur5.png"
MAP_PNG = REFERENCE / "map_planar.png"
SCENE_THETA = np.array([0.3, -1.2, 1.4, -0.6, -1.2, 0.4])
MAP_ARM = (1.0, 0.5, 0.25)


def scene_image(theta=SCENE_THETA, colors=None):
    """The UR5 at theta with a pose target and its end frame, rendered off screen."""
    import pyvista as pv

    from ikteach.pictures import scene

    pv.OFF_SCREEN = True
    saved = dict(scene.COLORS)
    try:
        if colors:
            scene.COLORS.update(colors)
        arm = ik.core.robots.ur5()
        target = np.asarray(ik.fk_pose(arm, SCENE_THETA + 0.25))
        p = scene.scene(arm, theta, target=target)
        image = scene.render(p)
        p.close()
        return image
    finally:
        scene.COLORS.clear()
        scene.COLORS.update(saved)


def map_image(lengths=MAP_ARM, n=96, cmap="viridis"):
    """Iterations-to-converge map of DLS for a planar arm, with its boundary and reach circles."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ikteach.pictures import workspace_maps as ws

    arm = ik.planar_chain(lengths)
    grid = ws.target_grid(arm, n)
    m = ws.sweep(arm, grid, [0.3, 0.6, 0.6], method="dls", damping=0.1, max_iter=30,
                 stall_tol=1e-3)
    fig, ax = plt.subplots(figsize=(4, 4), dpi=80)
    ws.plot_map(ax, m.iterations, grid, "DLS iterations",
                ws.boundary(m.status == "converged", grid), ws.reach_radii(lengths),
                cmap=cmap, vmin=0, vmax=30)
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
    plt.close(fig)
    return image


def ssim(a, b, crop_to=None):
    """Structural similarity of two RGB images (per channel, averaged). With crop_to (an
    image), both are cropped to the box around crop_to's coloured pixels (the arm, not the
    white or grey background), so a small change to the arm is not averaged away."""
    from skimage.metrics import structural_similarity

    a, b = np.asarray(a), np.asarray(b)
    if crop_to is not None:
        c = np.asarray(crop_to).astype(int)
        rows, cols = np.nonzero(c.max(axis=2) - c.min(axis=2) > 40)
        pad = 8
        r0, r1 = max(rows.min() - pad, 0), rows.max() + pad + 1
        c0, c1 = max(cols.min() - pad, 0), cols.max() + pad + 1
        a, b = a[r0:r1, c0:c1], b[r0:r1, c0:c1]
    return structural_similarity(a, b, channel_axis=2)


def read_png(path):
    from skimage.io import imread

    return imread(path)[..., :3]


if __name__ == "__main__":
    from skimage.io import imsave

    REFERENCE.mkdir(exist_ok=True)
    imsave(SCENE_PNG, scene_image(), check_contrast=False)
    imsave(MAP_PNG, map_image(), check_contrast=False)
    print("wrote", SCENE_PNG, MAP_PNG)
