"""import ikteach stays light: heavy libraries load on first use of the modules that need them."""
import subprocess
import sys

import pytest

HEAVY = ("matplotlib", "pyvista", "skimage", "ipywidgets")


def _run(code):
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return out.stdout.split()


def test_import_loads_no_heavy_library():
    code = "import sys, ikteach; print(*[m for m in %r if m in sys.modules])" % (HEAVY,)
    assert _run(code) == []


def test_lazy_modules_work_as_attributes():
    code = ("import sys, ikteach as ik; print('matplotlib' in sys.modules); "
            "ik.pictures.workspace_maps.target_grid; ik.pictures.plot.draw_arm; "
            "ik.pictures.demo.Demo; ik.pictures.scene.scene; ik.check.jacobian; "
            "from ikteach.pictures import tree_plot; ik.core.settle.settle_factor; "
            "print('matplotlib' in sys.modules, len(ik.__all__) <= 40, "
            "all(hasattr(ik, name) for name in ik.__all__))")
    assert _run(code) == ["False", "True", "True", "True"]


def test_an_unknown_attribute_is_an_attribute_error():
    code = ("import ikteach as ik\ntry:\n    ik.no_such_thing\nexcept AttributeError as e:\n"
            "    print('no_such_thing' in str(e))")
    assert _run(code) == ["True"]


def test_compilation_cache_folder_from_the_environment(tmp_path, monkeypatch):
    import jax
    from ikteach.course import notebook

    monkeypatch.setenv(notebook.CACHE_ENV, "off")
    assert notebook.default_cache_dir() is None
    assert notebook.compilation_cache() is None
    monkeypatch.setenv(notebook.CACHE_ENV, str(tmp_path / "jit"))
    assert notebook.default_cache_dir() == str(tmp_path / "jit")
    old = jax.config.jax_compilation_cache_dir
    try:
        assert notebook.compilation_cache() == str(tmp_path / "jit")
        assert jax.config.jax_compilation_cache_dir == str(tmp_path / "jit")
        assert (tmp_path / "jit").is_dir()
    finally:
        jax.config.update("jax_compilation_cache_dir", old)


@pytest.mark.parametrize("version, trusted", [("0.5.1", False), ("0.5.3", False), ("0.4.38", False),
                                              ("0.6.0", True), ("0.10.2", True), ("1.0.0rc1", True)])
def test_the_compilation_cache_is_used_only_where_jaxlib_loads_it_right(version, trusted):
    from ikteach.course import notebook

    assert notebook.cache_trusted(version) is trusted
