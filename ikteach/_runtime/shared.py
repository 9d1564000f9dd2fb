"""Fewer compiled programs: a method's kind and every number as data.

JAX compiles a program per distinct structure of its arguments. Two choices make the course's
solves share programs, without changing what any step computes:

one_of      a built-in method becomes one branch of a jax.lax.switch over one method of each
            built-in kind (the Jacobian methods together, CCD and FABRIK together), chosen by
            a traced index. Comparing six methods, sweeping lambda or alpha, or tracking with
            another method then runs the program the first solve compiled. Each branch is
            the method's own delta, called as the loop calls it.
as_data     every number of the arguments as a numpy value of a fixed dtype: a Python float
            (weak-typed for JAX) and a numpy float then make the same program (a rest gain or
            weights given after a solve without them used to compile again).
"""
import jax
import numpy as np


class OneOf:
    """The method members[index], as one branch of a switch over all members."""

    def __init__(self, index, members):
        self.index, self.members = index, tuple(members)

    uses_jacobian = property(lambda self: self.members[0].uses_jacobian)
    is_jax = True

    def delta(self, problem, theta, e, J, free=None):
        branches = [lambda m=m: m.delta(problem, theta, e, J, free) for m in self.members]
        if not isinstance(self.index, jax.core.Tracer):  # run eagerly: no switch needed
            return branches[int(self.index)]()
        return jax.lax.switch(self.index, branches)

    def resolved(self, length_scale):
        return self


jax.tree_util.register_pytree_node(
    OneOf, lambda m: ((m.index, m.members), None), lambda _, data: OneOf(*data))


def _structure(method):
    return type(method), jax.tree_util.tree_structure(method)


def one_of(method, kinds, length_scale):
    """method as a OneOf over one default method of each of `kinds` (classes) that shares its
    use of J, defaults resolved for an arm of this size, with `method` in its own place (a
    method whose structure no default has, e.g. JT with a fixed alpha, joins as an extra
    member). A method of another kind (a user's) comes back as it is."""
    if type(method) not in kinds:
        return method
    members = [kind().resolved(length_scale) for kind in kinds
               if kind.uses_jacobian == method.uses_jacobian]
    places = [k for k, m in enumerate(members) if _structure(m) == _structure(method)]
    if places:
        members[places[0]] = method
        index = places[0]
    else:
        members.append(method)
        index = len(members) - 1
    return OneOf(np.int64(index), members)


def as_data(tree):
    """Every leaf as a numpy value: floats as float64, integers as int64, booleans as bool
    (JAX arrays are kept as they are)."""
    def fixed(x):
        if isinstance(x, jax.Array):
            return x
        x = np.asarray(x)
        if x.dtype.kind == "f":
            return x.astype(np.float64)
        if x.dtype.kind in "iu":
            return x.astype(np.int64)
        return x
    return jax.tree_util.tree_map(fixed, tree)
