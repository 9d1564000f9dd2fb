"""A notebook's cell as plain Python, for tests that run the instructor's solutions in the test
process (the grader runs cells in IPython's shell instead: grading/cells.py)."""
from IPython.core.inputtransformer2 import TransformerManager

from ikteach.course.grading.extract import cell_body


def python_source(source):
    """Cell source with IPython syntax (magics, !shell) rewritten as plain Python."""
    return TransformerManager().transform_cell(cell_body(source))
