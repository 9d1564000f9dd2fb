"""The exercise notebooks: one source (the solutions), templates without solution code."""
import json
import re
from pathlib import Path

import nbformat
import pytest

from ikteach.course import exercises

ROOT = Path(__file__).resolve().parents[1]
SOLUTIONS = sorted((ROOT / "instructor" / "solutions").glob("*.ipynb"))
TEMPLATES = sorted((ROOT / "notebooks" / "exercises").glob("*.ipynb"))


def test_one_template_per_solution():
    assert len(SOLUTIONS) == 7
    assert [p.name for p in TEMPLATES] == [p.name for p in SOLUTIONS]


@pytest.mark.parametrize("solution", SOLUTIONS, ids=lambda p: p.name)
def test_template_is_built_from_its_solution(solution):
    """The committed template is what `python -m ikteach.course.exercises build` makes of it."""
    built = exercises.template_from(nbformat.read(solution, as_version=4))
    template = nbformat.read(ROOT / "notebooks" / "exercises" / solution.name, as_version=4)
    assert [c.source for c in template.cells] == [c.source for c in built.cells]
    assert template.metadata["ikteach"]["exercise"] == int(solution.name[:2])


@pytest.mark.parametrize("solution", SOLUTIONS, ids=lambda p: p.name)
def test_templates_contain_no_solution_code(solution):
    text = solution.read_text()
    book = nbformat.read(solution, as_version=4)
    answer_lines = [line for cell in book.cells for line in exercises.solution_lines(cell.source)
                    if not line.startswith(("#", '"""')) and re.search(r"\w", line)]
    assert answer_lines, "every solution notebook has answers between the markers"
    template = ROOT / "notebooks" / "exercises" / solution.name
    sources = "\n".join(c.source for c in nbformat.read(template, as_version=4).cells)
    outputs = json.dumps([c.get("outputs", []) for c in nbformat.read(template, 4).cells])
    assert exercises.BEGIN not in sources and exercises.END not in sources
    leaked = [line for line in answer_lines if line in sources or line in outputs]
    assert not leaked
    assert exercises.PLACEHOLDER in sources and exercises.BEGIN in text


@pytest.mark.parametrize("template", TEMPLATES, ids=lambda p: p.name)
def test_template_check_cells_say_not_yet_implemented(template):
    book = nbformat.read(template, as_version=4)
    first_code = next(c for c in book.cells if c.cell_type == "code").source
    assert 'if "google.colab" in sys.modules' in first_code
    assert "import ikteach as ik" in first_code and "rng = ik.notebook.setup()" in first_code
    outputs = [o for c in book.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    texts = [o.get("text", "") for o in outputs]
    assert any("not yet implemented" in t for t in texts)
    assert " " not in template.name


def test_strip_solutions_keeps_indentation_and_rejects_broken_markers():
    source = ("def f(x):\n    \"\"\"doc\"\"\"\n    ### BEGIN SOLUTION\n    y = x + 1\n"
              "    return y\n    ### END SOLUTION\n\nf")
    assert exercises.strip_solutions(source) == (
        f'def f(x):\n    """doc"""\n    {exercises.PLACEHOLDER}\n\nf')
    assert exercises.solution_lines(source) == ["y = x + 1", "return y"]
    with pytest.raises(ValueError, match="without"):
        exercises.strip_solutions("### BEGIN SOLUTION\nx = 1\n")
    with pytest.raises(ValueError, match="without"):
        exercises.strip_solutions("x = 1\n### END SOLUTION\n")


def test_build_writes_templates(tmp_path):
    (tmp_path / "sol").mkdir()
    for path in SOLUTIONS[:2]:
        (tmp_path / "sol" / path.name).write_text(path.read_text())
    written = exercises.build(tmp_path / "sol", tmp_path / "out", run=False)
    assert [p.name for p in written] == [p.name for p in SOLUTIONS[:2]]
    with pytest.raises(ValueError, match="solutions"):
        exercises.build(tmp_path / "empty", tmp_path / "out", run=False)
