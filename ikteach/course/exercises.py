"""Student templates from the instructor's solution notebooks: one source for both.

    python -m ikteach.course.exercises build [--solutions DIR] [--out DIR] [--no-execute]

Solution notebooks (instructor/solutions/NN_name.ipynb) carry the answers between
``### BEGIN SOLUTION`` and ``### END SOLUTION`` lines. Each such region becomes one
``raise NotImplementedError(...)`` line at the marker's indentation (in a Markdown answer cell:
"*(Write your answer here.)*"); outputs are cleared and
the templates are executed (so they are committed with their check cells' output,
"not yet implemented"). Anything outside the markers is copied as it is.
"""
import argparse
import re
import sys
from pathlib import Path

from .notebook_header import NOTATION_LINE, notation_link, with_notation
from .notebook_strip import strip_notebook

BEGIN = "### BEGIN SOLUTION"
END = "### END SOLUTION"
PLACEHOLDER = 'raise NotImplementedError("replace this line with your code")'
ANSWER_PLACEHOLDER = "*(Write your answer here.)*"  # in a Markdown cell (a written answer)
ROOT = Path(__file__).resolve().parents[2]
SOLUTIONS = ROOT / "instructor" / "solutions"
TEMPLATES = ROOT / "notebooks" / "exercises"


def strip_solutions(source, placeholder=PLACEHOLDER):
    """The cell source with every BEGIN/END SOLUTION region replaced by one placeholder line."""
    out, inside = [], False
    for number, line in enumerate(source.splitlines(), 1):
        stripped = line.strip()
        if stripped == BEGIN:
            if inside:
                raise ValueError(f"source: nested {BEGIN!r} at line {number}")
            inside = True
            indent = line[: len(line) - len(line.lstrip())]
            out.append(indent + placeholder)
        elif stripped == END:
            if not inside:
                raise ValueError(f"source: {END!r} without {BEGIN!r} at line {number}")
            inside = False
        elif not inside:
            out.append(line)
    if inside:
        raise ValueError(f"source: {BEGIN!r} without {END!r}")
    return "\n".join(out)


def solution_lines(source):
    """The lines between the markers (what must never reach a template)."""
    found = re.findall(rf"{re.escape(BEGIN)}\n(.*?)\n[ \t]*{re.escape(END)}", source, re.S)
    return [line.strip() for block in found for line in block.splitlines() if line.strip()]


def template_from(solution):
    """A template notebook (nbformat node) from a solution notebook node."""
    import nbformat

    book = nbformat.from_dict(solution)
    for cell in book.cells:
        if cell.cell_type == "code":
            cell.source = strip_solutions(cell.source)
            cell.outputs = []
            cell.execution_count = None
        elif cell.cell_type == "markdown" and BEGIN in cell.source:  # a written answer
            cell.source = strip_solutions(cell.source, ANSWER_PLACEHOLDER)
    first_text = next((c for c in book.cells if c.cell_type == "markdown"), None)
    if first_text is not None and NOTATION_LINE.search(first_text.source):  # linked from TEMPLATES
        first_text.source = with_notation(first_text.source, notation_link(TEMPLATES / "template.ipynb"))
    book.metadata.setdefault("ikteach", {})["template"] = True
    return book


def execute(book, cwd, timeout=120):
    """Run a notebook in place in a fresh kernel (cwd: its working directory)."""
    from nbclient import NotebookClient

    NotebookClient(book, timeout=timeout, kernel_name="python3",
                   resources={"metadata": {"path": str(cwd)}}).execute()
    return book


def build(solutions=SOLUTIONS, out=TEMPLATES, run=True):
    """Write one template per solution notebook; returns the written paths."""
    import nbformat

    solutions, out = Path(solutions), Path(out)
    sources = sorted(solutions.glob("[0-9][0-9]_*.ipynb"))
    if not sources:
        raise ValueError(f"solutions: expected NN_name.ipynb notebooks in {solutions}, found none")
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for path in sources:
        book = template_from(nbformat.read(path, as_version=4))
        if run:
            execute(book, out)
        strip_notebook(book)  # no run noise in the committed template
        target = out / path.name
        nbformat.write(book, target)
        written.append(target)
        print(f"wrote {target.relative_to(ROOT) if target.is_relative_to(ROOT) else target}")
    return written


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m ikteach.course.exercises",
                                     description="Build the student templates from the "
                                                 "instructor's solution notebooks.")
    sub = parser.add_subparsers(dest="command", required=True)
    b = sub.add_parser("build", help="write notebooks/exercises/ from instructor/solutions/")
    b.add_argument("--solutions", default=str(SOLUTIONS), help="solution notebooks folder")
    b.add_argument("--out", default=str(TEMPLATES), help="templates folder")
    b.add_argument("--no-execute", action="store_true", help="do not run the templates")
    args = parser.parse_args(argv)
    build(args.solutions, args.out, run=not args.no_execute)
    return 0


if __name__ == "__main__":
    sys.exit(main())
