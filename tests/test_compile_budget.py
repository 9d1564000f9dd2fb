"""The lectures' budgets of XLA programs (ikteach/course/warm.py: BUDGETS; the table is in
docs/maintainers.md) and `ikteach warm`. Each lecture is held to its budget on nbval's own run
of it (tests/lecture_budgets.py): one Run All serves both."""
import re
from pathlib import Path

from ikteach.course.warm import BUDGETS, count_programs, lectures

ROOT = Path(__file__).resolve().parents[1]


def test_every_lecture_has_a_budget_and_every_budget_a_lecture():
    assert {path.stem for path in lectures()} == set(BUDGETS)


def test_the_maintainers_table_states_the_budgets():
    text = (ROOT / "docs" / "maintainers.md").read_text()
    for name, budget in BUDGETS.items():
        row = re.search(rf"^\| `{name}` \|.*\| *{budget} *\|$", text, re.MULTILINE)  # last column
        assert row, f"docs/maintainers.md: no row for {name} with budget {budget}"


def test_over_its_budget_a_lecture_is_told_which_programs_it_needed():
    from lecture_budgets import over_budget

    within = {"programs": BUDGETS["01_jacobian"], "by_name": {"solve": [3, 0.5]}}
    assert over_budget("01_jacobian", within) is None
    over = dict(within, programs=BUDGETS["01_jacobian"] + 1)
    assert "01_jacobian" in over_budget("01_jacobian", over) and "'solve', [3" in over_budget(
        "01_jacobian", over)
    assert over_budget("01_jacobian", dict(within, programs=0))  # nothing counted: not run


def test_after_ikteach_warm_a_first_run_compiles_nothing(tmp_path, capsys):
    """`ikteach warm` fills the cache a lecture's first run then loads every program from."""
    from ikteach.course import warm

    lecture = lectures()[0]
    assert warm.main([str(lecture), "--cache", str(tmp_path)]) == 0
    assert "programs" in capsys.readouterr().out
    again = count_programs(lecture, cache=tmp_path)
    assert again["programs"] > 0 and again["compiled"] == 0, again


def test_ikteach_warm_says_when_the_cache_is_off(monkeypatch, capsys):
    from ikteach.course import warm

    monkeypatch.setenv("IKTEACH_JAX_CACHE", "off")
    assert warm.main([]) == 2
    assert "cache is off" in capsys.readouterr().err


def test_no_lecture_within_its_budget_reaches_the_program_bound():
    """The bound on compiled programs (ikteach/_runtime/jit.py) clears JAX's caches only past
    every lecture's budget: a lecture's Run All never clears them."""
    from ikteach._runtime import jit as runtime_jit

    assert max(BUDGETS.values()) <= runtime_jit.MAX_PROGRAMS
