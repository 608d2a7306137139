"""CPython's cyclic garbage collector, set for the simulation loop.

The loop allocates many short-lived objects (messages, small arrays) but makes few reference
cycles; with CPython's default thresholds (700, 10, 10) the collector runs a young pass every
700 allocations and, now and then, a full pass over every tracked object, including the
~10^6 that the imports (MuJoCo bindings, numba, scipy, onnxruntime) leave behind. Measured on
``auvsim bench mission`` (cssn_lawnmower), that is ~2 % of the loop's CPU time; with
:data:`LOOP_GC_THRESHOLDS` it is below 0.1 %. Reference counting still frees acyclic objects at
once; only cycles wait longer.
"""

from __future__ import annotations

import gc

#: (young, middle, old) thresholds of :func:`gc.set_threshold` while the simulator runs.
LOOP_GC_THRESHOLDS = (10_000, 50, 100)


def set_loop_thresholds() -> tuple[int, int, int]:
    """Apply :data:`LOOP_GC_THRESHOLDS`; returns the previous thresholds (to restore them)."""
    previous = gc.get_threshold()
    gc.set_threshold(*LOOP_GC_THRESHOLDS)
    return previous
