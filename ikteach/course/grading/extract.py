"""A notebook's code cells as text (the grader runs them in IPython's shell: cells.py), and the
same with magic and shell lines dropped (for the fingerprints, which compile a cell by itself);
a cell magic that runs its body as the cell's own Python (%%time, %%capture) is taken off first.
"""
import re

BODY_AS_PYTHON = re.compile(r"\s*%%(time|capture)\b[^\n]*(\n|$)")  # its body: plain cell code


def cell_body(source):
    """The cell without a leading %%time or %%capture (which run their body as the cell's own
    code: graded as that code, compiled as the cell's)."""
    while match := BODY_AS_PYTHON.match(source):
        source = source[match.end():]
    return source


def without_magics(source):
    """Cell source with its magic and shell lines dropped (cheap: for the grader's own process,
    which reads the code but never runs it)."""
    source = cell_body(source)
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
