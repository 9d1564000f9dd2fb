"""Private runtime support: jax.jit for the whole-loop programs (jit.py) and the CPU device
choice a notebook can opt into (devices.py)."""
