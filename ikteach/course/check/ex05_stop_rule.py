"""Exercise 5: stalled(delta_theta, lengths, fraction) and stop_rule_step(step, lengths, fraction).

Parts: the rule 5; the rule ending ik.solve 5 (the returned step function raises ik.StopSolve on
exactly the rule's cases, then ends an out-of-reach ik.solve "stalled" where the rule says: one
arm and target, in every draw; the seed adds rule cases).
"""
import functools

import numpy as np

from ...core.chain import planar_chain
from ...core.dls import dls_step as _ref_dls
from ...core.solve import StopSolve
from ...core.solve import solve as _solve
from ..grading.own_code import fixed_step
from .verdicts import (_as_array, _call, _Case, _close, _evaluate, _Fail, _fmt, _in_every_draw,
                       _Part, _rng, SOLVE_LIMIT)

NUMBER = 5
CHECK_NAME = "stop_rule"
TITLE = "the out-of-reach stop rule"
FUNCTIONS = ('stalled', 'stop_rule_step')
REFERENCES = ("ikteach.core.stop_rules:joint_steps",  # ikteach's answers, stubbed when graded
              "ikteach.core.stop_rules:motion",
              "ikteach.core.stop_rules:step_size",
)

STOP_ARM = [1.0, 1.0, 1.0]
STOP_TARGET = [4.0, 0.5]      # out of reach: the arm is 3 long
STOP_THETA0 = [0.3, 0.2, 0.1]
STOP_FRACTION = 1e-3
STOP_MAX_ITER = 300
STOP_DAMPING = 1.0            # enough damping for DLS to settle (exercise 6: less jitters)
NEVER_STOPPED = ("the solve never stopped: when the rule fires, raise ik.StopSolve from your "
                 "step function (ik.solve then ends \"stalled\").")


def _total(lengths):
    return float(np.sum(lengths))


def _sums(d, lengths, fraction):
    """The failing case's two sides of the rule, for the message."""
    return (f"threshold: {fraction * _total(lengths):.4g}, sum |delta_theta_i| = "
            f"{np.abs(d).sum():.4g}")


def _stalled_reference(delta_theta, lengths, fraction):
    """The report's rule: stop when sum |delta_theta_i| < fraction * (total link length)."""
    return float(np.sum(np.abs(delta_theta))) < fraction * _total(lengths)


# the step the student's stop rule wraps (a partial of ikteach's own function, so that the
# grader can hand it to the student's code in another process by its name)
_BASE_STEP = functools.partial(_ref_dls, damping=STOP_DAMPING)


_RULE_MISTAKES = [  # (a wrong rule, what to say), tried in this order against every case
    (lambda d, L, f: float(np.sum(np.abs(d))) <= f * _total(L),
     "use a strict <: at exactly the threshold the rule must not fire yet "
     "(sum |delta_theta_i| < fraction * (sum of lengths))."),
    (lambda d, L, f: float(np.sum(d)) < f * _total(L),
     "use absolute values: sum |delta_theta_i| - joints turning opposite ways do not cancel."),
    (lambda d, L, f: abs(float(np.sum(d))) < f * _total(L),
     "use absolute values: sum |delta_theta_i| - joints turning opposite ways do not cancel."),
    (lambda d, L, f: float(np.sum(np.abs(d))) < f,
     "the threshold must be proportional to the link lengths: fraction * (sum of the "
     "lengths), not just the fraction."),
    (lambda d, L, f: float(np.sum(np.abs(d))) < f * float(np.max(L)),
     "the threshold is fraction * (sum of the lengths), the whole arm's length - not the "
     "longest link."),
    (lambda d, L, f: float(np.linalg.norm(d)) < f * _total(L),
     "sum the joint steps (sum |delta_theta_i|), not their 2-norm (the length of "
     "delta_theta): the report's rule is the sum of the absolute steps."),
    (lambda d, L, f: float(np.max(np.abs(d))) < f * _total(L),
     "sum the joint steps (sum |delta_theta_i|), not their largest."),
    (lambda d, L, f: not _stalled_reference(d, L, f),
     "inverted: return True when the step is small (the arm has stopped moving: stop), "
     "False otherwise."),
]


HAND = [([0.1, -0.1], [1.0, 1.0], 1e-3), ([2e-3, 0.0, 0.0], [1.0, 1.0, 1.0], 1e-3),
        ([1e-3, 1e-3, 1e-3], [1.0, 1.0, 1.0], 1e-3), ([0.05, 0.05], [10.0, 20.0], 1e-3),
        ([-1e-3, 5e-4], [2.0, 1.0], 1e-3), ([0.5], [1.0], 1e-3),
        ([5e-4, 5e-4], [0.5, 0.5], 1e-3),  # exactly at the threshold
        ([6e-4, 6e-4], [0.5, 0.5], 1e-3),  # each joint below it, their sum above
        ([8e-4, 8e-4], [0.5, 0.5], 1e-3)]  # each joint below it, their 2-norm above


def _hidden_hand(rng):
    """HAND turned: joints reordered, steps and lengths scaled by one power of 2 (the sums and
    the threshold scale exactly: a case at the threshold stays there)."""
    out = []
    for d, L, f in HAND:
        order, scale = rng.permutation(len(d)), 2.0 ** float(rng.choice([-1, 1, 2]))
        out.append(((np.array(d)[order] * scale).tolist(), (np.array(L)[order] * scale).tolist(),
                    f))
    return out


@_in_every_draw
def _stop_cases(seed=None):
    rng = _rng(seed, 5)
    hand = list(HAND if seed is None else _hidden_hand(rng))
    for _ in range(10):
        n = int(rng.integers(1, 6))
        lengths = rng.uniform(0.3, 3.0, n).round(3)
        fraction = float(rng.choice([1e-3, 1e-2, 1e-4]))
        size = fraction * lengths.sum() * float(rng.choice([0.4, 2.5]))
        w = rng.dirichlet(np.ones(n)) * size * rng.choice([-1.0, 1.0], n)
        hand.append((w.tolist(), lengths.tolist(), fraction))
    return [_Case((np.array(d), list(L), f),
                  f"delta_theta = {_fmt(d)}, lengths = {_fmt(L)}, fraction = {f:g}",
                  size=len(d) * 100 + k) for k, (d, L, f) in enumerate(hand)]


def _as_bool(value, name, case):
    """A True/False answer (a bool, or a number or 0-d array of one), or a _Fail."""
    arr = np.asarray(value) if value is not None else None
    if arr is not None and arr.shape == () and arr.dtype.kind in "biuf":
        return bool(arr)
    raise _Fail(f"`{name}` returned {type(value).__name__} {value!r:.60} on {case}; "
                "expected True or False")


_EXPECTED_STOP = {}  # the reference's stalled solve (the same in every draw), run once


def verdict(stalled, stop_rule_step, seed=None):
    """Verdict for exercise 5 without printing (`seed`: the grader's hidden cases)."""
    names = FUNCTIONS

    def rule():
        cases = _stop_cases(seed)
        answers = [_as_bool(_call(stalled, names[0], case, case.args[0].copy(),
                                  list(case.args[1]), case.args[2]), names[0], case)
                   for case in cases]
        wrong = [(case, got) for case, got in zip(cases, answers)
                 if got != _stalled_reference(*case.args)]
        if not wrong:
            return None
        case, got = wrong[0]
        d, lengths, fraction = case.args
        detail = (f"\n  smallest failing case: {case}\n  {_sums(d, lengths, fraction)}"
                  f"\n  expected {not got}, you returned {got}")
        # the diagnosis: the known mistake that gives the student's answer on every case
        for mistake, advice in _RULE_MISTAKES:
            if all(got == mistake(*c.args) for c, got in zip(cases, answers)):
                return advice + detail
        return "stop when sum |delta_theta_i| < fraction * (sum of lengths)." + detail

    def reference_step(J, e):
        delta = np.asarray(_BASE_STEP(J, e))
        if _stalled_reference(delta, STOP_ARM, STOP_FRACTION):
            raise StopSolve("out of reach")
        return delta

    def run_solve(step, name):
        case = (f"ik.solve(ik.planar_chain({STOP_ARM}), target={STOP_TARGET}, "
                f"theta0={STOP_THETA0}, method=your step, stall_tol=0)")
        arm = planar_chain(STOP_ARM)  # one arm and target, in every draw

        def go():
            return _solve(arm, np.array(STOP_TARGET), np.array(STOP_THETA0), method=step,
                          stall_tol=0.0, max_iter=STOP_MAX_ITER)
        try:
            return _call(go, name, case, limit=SOLVE_LIMIT), case
        except _Fail as exc:
            raise type(exc)(str(exc).replace(f" on {case}", f" inside {case}")) from None

    def wrapper_on_the_rules_cases():
        """stop_rule_step(step, lengths, fraction) wrapping a step that returns delta_theta
        (own_code.fixed_step): it must raise ik.StopSolve on exactly the cases where the rule
        fires, and pass the step on otherwise - whatever the arm of the solve below does."""
        for case in _stop_cases(seed):
            d, lengths, fraction = case.args
            text = (f"stop_rule_step(step, lengths={_fmt(lengths)}, fraction={fraction:g}) with "
                    f"a step that returns delta_theta = {_fmt(d)}")
            given = functools.partial(fixed_step, delta=[float(x) for x in d])
            step = _call(stop_rule_step, names[1], text, given, list(lengths), fraction)
            if not callable(step):
                return None  # said by the solve part
            stop = _stalled_reference(d, lengths, fraction)
            try:
                got = _call(step, "the step stop_rule_step returns", text, np.eye(len(d)),
                            d.copy())
            except StopSolve:
                if stop:
                    continue
                return ("your step function raised ik.StopSolve where the rule does not fire."
                        f"\n  smallest failing case: {text}\n  {_sums(d, lengths, fraction)}: "
                        "the step must go on")
            if stop:
                return (NEVER_STOPPED + f"\n  smallest failing case: {text}\n  "
                        f"{_sums(d, lengths, fraction)}: expected ik.StopSolve")
            got = _as_array(got, "the step stop_rule_step returns", text)
            if not _close(got, d):
                return (f"your step function must return the wrapped step's delta_theta "
                        f"unchanged when the rule does not fire.\n  smallest failing case: "
                        f"{text}\n  expected: {_fmt(d)}\n  yours:    {_fmt(got)}")

    def solve_part():
        problem = wrapper_on_the_rules_cases()
        if problem is not None:
            return problem
        case = (f"stop_rule_step(step, lengths={STOP_ARM}, fraction={STOP_FRACTION:g}) "
                f"with step = DLS (damping {STOP_DAMPING:g})")
        step = _call(stop_rule_step, names[1], case, _BASE_STEP, list(STOP_ARM), STOP_FRACTION)
        if not callable(step):
            return (f"`{names[1]}` must return a step function step(J, e) -> delta_theta; "
                    f"it returned {type(step).__name__}.")
        got, text = run_solve(step, names[1])
        if not _EXPECTED_STOP:
            _EXPECTED_STOP["iterations"] = run_solve(reference_step, "reference")[0].iterations
        want = _EXPECTED_STOP["iterations"]
        detail = (f"\n  case: {text}, target out of reach\n  expected: stalled after "
                  f"{want} iterations\n  yours:    {got.status} after "
                  f"{got.iterations} iterations")
        if got.status == "stalled" and abs(got.iterations - want) <= 1:
            return None
        if got.status == "max_iter":
            return NEVER_STOPPED + detail
        return "the stop rule did not end the solve where it should." + detail

    return _evaluate(NUMBER, TITLE, list(FUNCTIONS),
                     [_Part("rule", 5, rule), _Part("solve", 5, solve_part)])
