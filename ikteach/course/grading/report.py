"""The grader's outputs: one CSV row per student (ex1..ex7, total, the sandbox it ran in, notes:
why a notebook was not graded, copied: graded code that is ikteach's own answer, for the
instructor to judge) and one feedback file per student. Every text is printable UTF-8, no
control or bidi character in it (grading/submissions.text; the feedback keeps its newlines),
whatever the file names and notebooks held; no CSV cell starts a spreadsheet formula; each
student's name is NFC-normalised, or written with escapes where two names differ only in
normalisation, and with a hash of the folder's bytes where two still look alike (labels()):
every folder its own row and feedback file, whose name is short whatever the student's."""
import csv
import hashlib
import os
import unicodedata

from ..check.registry import NUMBERS as EXERCISE_NUMBERS
from ..check.verdicts import POINTS
from .submissions import text

FORMULA_START = ("=", "+", "-", "@", "\t", "\r")
MAX_FILE_NAME = 120  # bytes of a feedback file's name before its hash
RERUN = ("a check ran past its time limit and was run again in a fresh sandbox: the marks "
         "are the second run's")


def cell(value):
    """A CSV cell a spreadsheet shows as text: a leading ' where it would start a formula."""
    value = str(value)
    return "'" + value if value.startswith(FORMULA_START) else value


def labels(students):
    """{folder name: the name its row shows}, different for any two folders: NFC, unless
    another folder has the same NFC (then the raw name with every non-ASCII character escaped,
    so that the rows differ visibly); names that still look alike (a folder literally named
    `M\\xfcller` beside one whose name is the Latin-1 bytes) or differ only in case (one
    feedback file on macOS or Windows) get a short hash of the folder's own bytes, again while
    any two still clash (a folder named as another's hashed label)."""
    shown = {s: unicodedata.normalize("NFC", text(s)) for s in students}
    clashes = {n for n in shown.values() if list(shown.values()).count(n) > 1}
    shown = {s: (text(s).encode("ascii", "backslashreplace").decode() if n in clashes else n)
             for s, n in shown.items()}
    digits = 8
    while True:  # until unique: a folder may be named as another's hashed label
        folded = [n.casefold() for n in shown.values()]
        if len(set(folded)) == len(folded):
            return shown
        shown = {s: (f"{n} [{hashlib.sha256(os.fsencode(s)).hexdigest()[:digits]}]"
                     if folded.count(n.casefold()) > 1 else n) for s, n in shown.items()}
        digits = 64  # the whole hash from the second round: no crafted clash of 8 digits


def file_name(label):
    """A feedback file name for `label` that any file system holds (long names: cut + hash)."""
    name = label.replace("/", "_").lstrip(".") or "_"
    raw = name.encode("utf-8")
    if len(raw) <= MAX_FILE_NAME:
        return name + ".txt"
    digest = hashlib.sha256(raw).hexdigest()[:12]
    return raw[:MAX_FILE_NAME].decode("utf-8", "ignore") + "-" + digest + ".txt"


def _feedback_text(student, results):
    lines = [f"Feedback for {student}", ""]
    by_number = _best(results)  # the CSV's choice
    for number in EXERCISE_NUMBERS:
        r = by_number.get(number)
        if r is None:
            lines.append(f"Exercise {number}: 0/{POINTS} - no notebook submitted")
            continue
        how = (f", taken as exercise {number} {r['how']}"
               if r.get("how") not in (None, "by its metadata") else "")
        lines.append(f"Exercise {number} ({r['file']}{how}): {r['score']:g}/{r['max']:g}")
        lines += [f"  not counted (the best notebook counts): {o['file']}: {o['score']:g}/"
                  f"{o['max']:g} - {o['message'].splitlines()[0][:200] if o['message'] else ''}"
                  for o in results if o["exercise"] == number and o is not r]
        lines += [f"  {line}" for line in r["message"].splitlines()]
        lines += [f"  note: {note}" for note in r["notes"]]
        copied = r.get("copied", [])
        lines += [f"  for the instructor: {line}" for line in copied]
        if copied:
            lines.append("  (compiled code compared, names and docstrings ignored; the marks "
                         "stand until the instructor decides)")
        if r.get("answer", "").strip():
            lines.append("  your written answer (not marked by the checker; read by the "
                         "instructor):")
            lines += [f"    | {line}" for line in r["answer"].strip().splitlines()]
    for r in results:
        if r["exercise"] is None:
            lines.append(f"{r['file']}: {r['message']}")
    total = sum(r["score"] for r in by_number.values())
    lines += ["", f"Total: {total:g}/{POINTS * len(EXERCISE_NUMBERS)}"]
    return "\n".join(lines) + "\n"


def _best(results):
    """One result per exercise (the best, if a student handed in two for the same one)."""
    best = {}
    for r in results:
        number = r["exercise"]
        if number is not None and (number not in best or r["score"] > best[number]["score"]):
            best[number] = r
    return best


def write_results(per_student, notes, out, feedback, backend):
    feedback.mkdir(parents=True, exist_ok=True)
    rows, shown = [], labels(per_student)
    for student, results in per_student.items():
        best = _best(results)
        row = {"student": shown[student]}
        for number in EXERCISE_NUMBERS:
            row[f"ex{number}"] = best[number]["score"] if number in best else 0.0
        row["total"] = sum(row[f"ex{n}"] for n in EXERCISE_NUMBERS)
        row["sandbox"] = backend
        row["notes"] = text(" | ".join(notes[student]))[:2000]
        row["copied"] = text(" | ".join(f"ex{n}: {line}" for n in EXERCISE_NUMBERS
                                        if n in best for line in best[n].get("copied", [])))
        rows.append(row)
        page = _feedback_text(row["student"], results)
        if notes[student] and not results:
            page += "".join(f"note: {n}\n" for n in notes[student])
        (feedback / file_name(row["student"])).write_text(text(page, lines=True),
                                                          encoding="utf-8")
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w", newline="", encoding="utf-8") as handle:
        columns = ["student", *(f"ex{n}" for n in EXERCISE_NUMBERS), "total", "sandbox", "notes",
                   "copied"]
        writer = csv.DictWriter(handle, fieldnames=columns)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:g}" if isinstance(v, float) else cell(v))
                             for k, v in row.items()})
    return rows


