"""Moved: the grader is `ikteach grade SUBMISSIONS --out grades.csv` (or
`python -m ikteach.course.grade`). This shim keeps last term's `python -m ikteach.grade ...`
scripts working: it says so on stderr and runs the grader with the same arguments."""
import sys

if __name__ == "__main__":
    print("python -m ikteach.grade has moved: use `ikteach grade ...` "
          "(running it for you now)", file=sys.stderr)
    from ikteach.course.cli import main

    sys.exit(main(["grade", *sys.argv[1:]]))
