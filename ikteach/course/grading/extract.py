"""The student's code as the checks see it: top-level imports, definitions and assignments of
the notebook's code cells, taken from the source by the AST - never from a kernel's memory.

Magics and shell lines are turned into Python by IPython's transformer (so a cell with `%pip`
still parses) and then dropped with every other statement kind (calls, loops, ifs, prints):
only what defines names reaches the checks' worker. A cell magic that runs its body as the
cell's own Python (%%time, %%capture) is taken off first: the body is graded as if it stood
alone. The transformer is slow on long runs of magics, so it runs in the checks' worker (under
its time limit), never in the grader's process.
"""
import ast
import re

KEPT = (ast.Import, ast.ImportFrom, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef,
        ast.Assign, ast.AnnAssign)
BODY_AS_PYTHON = re.compile(r"\s*%%(time|capture)\b[^\n]*(\n|$)")  # its body: plain cell code


def python_source(source):
    """Cell source with IPython syntax (magics, !shell) rewritten as plain Python."""
    while match := BODY_AS_PYTHON.match(source):
        source = source[match.end():]
    try:
        from IPython.core.inputtransformer2 import TransformerManager
    except ImportError:  # no IPython: drop the magic lines instead
        return without_magics(source)
    return TransformerManager().transform_cell(source)


def without_magics(source):
    """Cell source with its magic and shell lines dropped (cheap: for the grader's own process,
    which reads the code but never runs it)."""
    while match := BODY_AS_PYTHON.match(source):
        source = source[match.end():]
    return "\n".join("" if line.lstrip().startswith(("%", "!")) else line
                     for line in source.splitlines())


def code_cells(book):
    """[(cell number (1-based), source as written)] of a notebook dict's code cells."""
    cells = []
    for index, cell in enumerate(book.get("cells", [])):
        if isinstance(cell, dict) and cell.get("cell_type") == "code":
            source = cell.get("source", "")
            cells.append((index + 1, "".join(map(str, source)) if isinstance(source, list)
                          else str(source)))
    return cells


def kept_statements(source):
    """The top-level statements of one cell (as written, magics included) the checks keep (a
    list of AST nodes); raises SyntaxError for a cell that is not Python."""
    return [node for node in ast.parse(python_source(source)).body if isinstance(node, KEPT)]
