"""Frozen dataclasses that travel into compiled code as pytrees (JAX's public registry).

Numbers (data fields) are traced, so new values reuse a compiled program; the other fields
are part of the program's key. JAX rebuilds the object from tracers without __post_init__,
so an object's checks run when a user makes it, never on tracers.
"""
import dataclasses

import jax


def pytree_dataclass(data, meta=()):
    """Decorator: a frozen dataclass registered as a pytree with these data and meta fields."""
    def register(cls):
        cls = dataclasses.dataclass(frozen=True)(cls)
        names = tuple(data) + tuple(meta)

        def flatten(obj):
            return [getattr(obj, k) for k in data], tuple(getattr(obj, k) for k in meta)

        def unflatten(meta_values, data_values):
            obj = object.__new__(cls)
            for name, value in zip(names, tuple(data_values) + tuple(meta_values)):
                object.__setattr__(obj, name, value)
            return obj

        jax.tree_util.register_pytree_node(cls, flatten, unflatten)
        return cls
    return register


def replace(obj, **changes):
    """obj with some fields changed, without running its checks again."""
    new = object.__new__(type(obj))
    for field in dataclasses.fields(obj):
        object.__setattr__(new, field.name, changes.get(field.name, getattr(obj, field.name)))
    return new
