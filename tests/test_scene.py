"""pyvista scenes: off-screen rendering, image regression against a committed reference."""
import base64
import importlib.util
import io

import numpy as np
import pytest

import ikteach as ik
from ikteach.pictures import backend_3d
from ikteach.pictures import scene

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
    arm = ik.core.robots.iiwa14()
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


def test_a_moved_scene_looks_like_one_built_at_the_new_pose(reference):
    """solve_gif builds its scene once and moves the arm's meshes rigidly from frame to frame:
    moved from another pose, the scene renders as one built at SCENE_THETA does."""
    import pyvista as pv

    pv.OFF_SCREEN = True
    arm = ik.core.robots.ur5()
    target = np.asarray(ik.fk_pose(arm, SCENE_THETA + 0.25))
    p, pose = scene._scene(arm, SCENE_THETA - 0.4, target, None, scene.WINDOW, None, None)
    assert ssim(reference, scene.render(p), crop_to=reference) < SCENE_SSIM  # not there yet
    scene._move_arm(pose, arm, SCENE_THETA)
    moved = scene.render(p)
    p.close()
    assert ssim(reference, moved, crop_to=reference) > SCENE_SSIM


@pytest.mark.parametrize("seed", range(5))
def test_turn_onto_takes_one_direction_onto_another(seed):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    for b in (rng.normal(size=3), -a, a):
        b = b / np.linalg.norm(b)
        R = scene.turn_onto(a, b)
        np.testing.assert_allclose(R @ a, b, atol=1e-12)
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)


def test_solve_gif_writes_frames(tmp_path, monkeypatch):
    import pyvista as pv

    arm = ik.core.robots.ur5()
    target = np.asarray(ik.fk_pose(arm, SCENE_THETA + 0.2))
    res = ik.solve(arm, target, SCENE_THETA, tol=1e-6, damping=0.05, max_iter=100)
    renders = []
    original = pv.Plotter.render
    monkeypatch.setattr(pv.Plotter, "render", lambda self: renders.append(1) or original(self))
    path = scene.solve_gif(arm, res.trace.theta, tmp_path / "solve.gif", target=target, frames_max=5)
    # one render per frame: adding a mesh to a plotter that has rendered once re-renders it
    # unless told not to, about 25 extra renders per frame
    assert len(renders) <= 2 * 5
    from PIL import Image

    with Image.open(path) as gif:
        assert gif.n_frames == min(5, len(res.trace.theta))
        assert gif.size == (320, 240)
    view = scene.show_gif(path, "a UR5 reaching")
    data, meta = view._repr_mimebundle_()
    assert data["text/html"].startswith('<img alt="a UR5 reaching" src="data:image/gif;base64,')
    png = base64.b64decode(data["image/png"])
    assert png.startswith(b"\x89PNG") and "a UR5 reaching" in meta["image/png"]["alt"]
    with Image.open(io.BytesIO(png)) as still, Image.open(path) as gif:
        gif.seek(gif.n_frames - 1)
        assert np.array_equal(np.asarray(still.convert("RGB")), np.asarray(gif.convert("RGB")))


@pytest.fixture
def backend():
    """Restore pyvista's backend and off-screen flag after a test that changes them."""
    pv = pytest.importorskip("pyvista")
    saved = pv.global_theme.jupyter_backend, pv.OFF_SCREEN
    yield pv
    pv.global_theme._jupyter_backend, pv.OFF_SCREEN = saved


def _arm_scene():
    arm = ik.planar_chain([1.0, 1.0, 1.0])
    return scene.scene(arm, np.array([0.3, 0.2, 0.1]), target=[2.0, 1.0], window_size=(160, 120))


def test_static_backend_displays_a_png_with_alt_text(backend, monkeypatch):
    shown = []
    monkeypatch.setattr("IPython.display.display", lambda obj: shown.append(obj))
    ik.notebook.setup(pyvista="static")
    assert backend.global_theme.jupyter_backend == "static"
    assert scene.show(_arm_scene()) is None
    (image,) = shown  # an <img> with alt text (JupyterLab ignores alt in image metadata)
    assert 'src="data:image/png;base64,iVBORw0KGgo' in image.data
    alt = image.data.split('alt="')[1].split('"')[0]
    assert "3-joint arm" in alt and "target at (2.00, 1.00, 0.00)" in alt
    tip = np.asarray(ik.fk(ik.planar_chain([1.0, 1.0, 1.0]), np.array([0.3, 0.2, 0.1])))
    assert f"{np.linalg.norm(tip - [2.0, 1.0]):.2f} from the end effector" in alt


def test_the_alt_text_says_what_a_reached_target_and_a_trail_look_like():
    """A reached target sits inside the end effector's frame: the alt text must not promise a
    visible purple target; the trail is named with its start and length."""
    arm = ik.core.robots.ur5()
    start = np.array([0.3, -1.2, 1.4, -0.6, -1.2, 0.4])
    target = np.asarray(ik.fk_pose(arm, start + 0.3))
    res = ik.solve(arm, target, start, method="dls", tol=1e-6, damping=0.01)
    trail = np.asarray(ik.pictures.workspace_maps.end_path(arm, res.trace.theta))
    alt = scene.describe(arm, res.theta, target=target, trail=trail, ghost=start)
    assert "at the end effector, hidden by its frame (reached)" in alt
    length = np.linalg.norm(np.diff(trail, axis=0), axis=1).sum()
    assert f"thin red tube {length:.2f} long" in alt and f"({trail[0, 0]:.2f}, " in alt
    away = scene.describe(arm, start, target=target)
    assert "hidden" not in away and "from the end effector" in away


def test_interactive_backend_hands_the_plotter_to_pyvista_even_off_screen(backend, monkeypatch):
    if importlib.util.find_spec("trame_vtk") is None:  # no `3d` extra: stand in for pyvista
        monkeypatch.setattr(backend, "set_jupyter_backend",
                            lambda name: setattr(backend.global_theme, "_jupyter_backend", name))
    monkeypatch.setenv("PYVISTA_OFF_SCREEN", "true")  # headless, as under test
    ik.notebook.setup(pyvista="interactive")
    assert backend.OFF_SCREEN and backend.global_theme.jupyter_backend == "trame"
    plotter, calls = _arm_scene(), []
    monkeypatch.setattr(plotter, "show", lambda **kw: calls.append(kw) or "live view")
    assert scene.show(plotter) == "live view"
    assert calls == [{"jupyter_backend": "trame"}]
    plotter.close()


def test_interactive_without_trame_says_what_to_run_and_stays_static(backend, monkeypatch, capsys):
    def no_trame(name):
        if name != "static":
            raise ImportError("Please install trame dependencies")
        backend.global_theme._jupyter_backend = name

    monkeypatch.setattr(backend, "set_jupyter_backend", no_trame)
    assert backend_3d._setup_pyvista("interactive") == "static"
    assert backend.global_theme.jupyter_backend == "static"
    said = capsys.readouterr().err
    assert "make lab" in said and "pip install 'ikteach[3d]'" in said
    assert "ikteach/" not in said and ".py" not in said  # no path inside the package


@pytest.mark.parametrize("choice, headless, expected", [
    ("static", False, "static"), ("interactive", True, "trame"),
    (None, True, "static"), (None, False, "trame")])
def test_pyvista_backend_choice(choice, headless, expected):
    assert ik.notebook.pyvista_backend(choice, headless) == expected


def test_a_bad_pyvista_choice_is_a_value_error_naming_the_parameter():
    with pytest.raises(ValueError, match="pyvista must be one of"):
        ik.notebook.setup(pyvista="live")
