"""Which exercise a student's notebook answers: by what it does (the functions it defines, the
check it calls), else its metadata, else an NN_ in its file name."""
import re
from pathlib import Path

from .report import EXERCISE_NUMBERS


def _from_name(path):
    """The exercise a file's name gives: its first NN_ that is an exercise's number (so Colab's
    "Copy of 02_jt_step.ipynb" and a download's "02_jt_step (1).ipynb" are exercise 2)."""
    for match in re.finditer(r"(?<!\d)(\d+)_", Path(path).name):
        if int(match.group(1)) in EXERCISE_NUMBERS:
            return int(match.group(1))
    return None


def _from_content(book):
    """(exercise, why) from what the code cells define and check - every graded function of
    exactly one exercise defined, or one exercise's check called; (None, None) otherwise.
    Regular expressions on the text (linear: nothing here parses a student's code)."""
    from .. import check
    from .extract import code_cells

    source = "\n".join(text_ for _, text_ in code_cells(book))
    defined = set(re.findall(r"^def[ \t]+(\w+)[ \t]*\(", source, re.M))
    checked = set(re.findall(r"^[ \t]*ik\.check\.(\w+)[ \t]*\(", source, re.M))
    found = [n for n, m in check.EXERCISES.items() if set(m.FUNCTIONS) <= defined]
    if len(found) > 1:  # several exercises' names defined: the one whose check is called
        found = [n for n in found if check.EXERCISES[n].CHECK_NAME in checked] or found
    if len(found) == 1:
        names = ", ".join(f"`{f}`" for f in check.EXERCISES[found[0]].FUNCTIONS)
        return found[0], f"by its content (it defines {names})"
    called = [n for n, m in check.EXERCISES.items() if m.CHECK_NAME in checked]
    if len(called) == 1:
        return called[0], ("by its content (it calls "
                           f"ik.check.{check.EXERCISES[called[0]].CHECK_NAME})")
    return None, None


def identify(path, book):
    """(exercise number or None, how it was recognised), content first: a student who started
    exercise 3 from the exercise 2 file keeps exercise 2's metadata (ikteach.exercise)."""
    meta = book.get("metadata") if isinstance(book, dict) else None
    meta = meta.get("ikteach") if isinstance(meta, dict) else None
    said = meta.get("exercise") if isinstance(meta, dict) else None
    said = said if isinstance(said, int) and said in EXERCISE_NUMBERS else None
    number, why = _from_content(book) if isinstance(book, dict) else (None, None)
    if number is not None and number != said:
        return number, why + (f"; its metadata says exercise {said}" if said else "")
    if said is not None:
        return said, "by its metadata"
    number = _from_name(path)
    return (number, "by its file name") if number is not None else (None, None)


def exercise_number(path, book):
    """The exercise a notebook answers (identify()'s number)."""
    return identify(path, book)[0]
