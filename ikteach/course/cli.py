"""The course's one command: `ikteach COMMAND ...` ([project.scripts] in pyproject.toml).

    ikteach grade SUBMISSIONS --out grades.csv [options]   grade a class (python -m ikteach.course.grade)
    ikteach exercises build                                 templates from the solutions
    ikteach site [--out build/site]                         the course as a static book
    ikteach slides [--out build/site/slides] [NOTEBOOK ...] reveal.js decks of the lectures
    ikteach header [--check] [--ref TAG]                    Colab cells and badges from pyproject.toml
    ikteach warm [NOTEBOOK ...] [--cache DIR]               compile the lectures' solvers before class

The names stay when the modules behind them move: a lecturer's script calls `ikteach grade`,
never a module path. `ikteach COMMAND --help` shows a command's own options.
"""
import argparse
import importlib
import sys

COMMANDS = {
    "grade": ("ikteach.course.grade", "grade the students' exercise notebooks into a CSV"),
    "exercises": ("ikteach.course.exercises", "`exercises build`: the templates from the solutions"),
    "site": ("ikteach.course.book", "build the course as a static HTML book (build/site)"),
    "slides": ("ikteach.course.slides", "build reveal.js slides of the lectures (build/site/slides)"),
    "header": ("ikteach.course.notebook_header", "write the Colab cells and badges (make header)"),
    "warm": ("ikteach.course.warm", "compile every lecture's solvers into the cache, before class"),
}


def parser():
    listing = "\n".join(f"  {name:10} {help_}" for name, (_, help_) in COMMANDS.items())
    p = argparse.ArgumentParser(prog="ikteach", usage="ikteach COMMAND [ARGUMENTS ...]",
                                description=__doc__.split("\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=f"commands:\n{listing}\n\n"
                                       "`ikteach COMMAND --help` for a command's options.")
    p.add_argument("command", metavar="COMMAND", choices=COMMANDS,
                   help="one of: " + ", ".join(COMMANDS))
    return p


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    args = parser().parse_args(argv[:1])  # exits with a clear message on a wrong command
    module = importlib.import_module(COMMANDS[args.command][0])
    return module.main(argv[1:])


if __name__ == "__main__":
    sys.exit(main())
