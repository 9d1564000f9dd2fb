"""The grader's outputs: one CSV row per student (ex1..ex7, total, the sandbox it ran in, notes:
why a notebook was not graded, copied: graded code that is ikteach's own answer, for the
instructor to judge) and one feedback file per student. Every text is printable UTF-8
(grading/submissions.text), whatever the file names and notebooks held."""
import csv

from ..check.registry import NUMBERS as EXERCISE_NUMBERS
from ..check.verdicts import POINTS
from .submissions import text


def _feedback_text(student, results):
    lines = [f"Feedback for {student}", ""]
    by_number = {r["exercise"]: r for r in results if r["exercise"] is not None}
    for number in EXERCISE_NUMBERS:
        r = by_number.get(number)
        if r is None:
            lines.append(f"Exercise {number}: 0/{POINTS} - no notebook submitted")
            continue
        lines.append(f"Exercise {number} ({r['file']}): {r['score']:g}/{r['max']:g}")
        for line in r["message"].splitlines():
            lines.append(f"  {line}")
        for note in r["notes"]:
            lines.append(f"  note: {note}")
        for line in r.get("copied", []):
            lines.append(f"  for the instructor: {line} (compiled code compared, names and "
                         "docstrings ignored); the marks stand until the instructor decides")
        if r.get("answer", "").strip():
            lines.append("  your written answer (not marked by the checker; read by the "
                         "instructor):")
            lines += [f"    | {line}" for line in r["answer"].strip().splitlines()]
    for r in results:
        if r["exercise"] is None:
            lines.append(f"{r['file']}: {r['message']}")
    total = sum(r["score"] for r in by_number.values())
    lines += ["", f"Total: {total:g}/{POINTS * len(EXERCISE_NUMBERS)}"]
    return text("\n".join(lines) + "\n")


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
    rows = []
    for student, results in per_student.items():
        best = _best(results)
        row = {"student": text(student)}
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
        (feedback / f"{row['student'].replace('/', '_')}.txt").write_text(page, encoding="utf-8")
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=["student"] + [f"ex{n}" for n in
                                                                  EXERCISE_NUMBERS]
                                + ["total", "sandbox", "notes", "copied"])
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:g}" if isinstance(v, float) else v) for k, v in row.items()})
    return rows


