"""SHA-256 over every byte an FLS render returns: the check that a faster renderer changed none.

:func:`update_with_render` feeds one :class:`sim.sensors.fls.FlsRender` into a hash: the fan
and polar images, the polar and fan label masks, the mean and realised intensities, the pose,
each object's truth record (floats by ``repr``, arrays by their bytes) and the state of the
noise generator after the frame (so the next frame's noise is covered too). Used by
``scripts/fls_frame_digest.py`` (A/B between two versions of the code on one machine) and
:mod:`sim.bench.fls_reference` (the digests of the pinned reference). The bytes of the
floating-point parts depend on the machine's numerics (CPU kernels, library versions), so a
digest compares renders of one machine and one set of versions only.
"""

from __future__ import annotations

import numpy as np


def update_with_render(h, render, rng: np.random.Generator) -> None:
    """Feed ``render`` (an :class:`sim.sensors.fls.FlsRender`) and ``rng``'s state into
    ``h`` (a ``hashlib`` hash object)."""
    f, t = render.frame, render.truth
    for a in (f.polar, f.fan, t.mask_polar, t.mask_fan, render.mean_intensity, render.intensity, t.pos_ned, t.R_ns):
        a = np.asarray(a)
        h.update(f"{a.dtype}{a.shape}".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(repr((f.t_s, t.t_s)).encode())
    for o in t.objects:
        fields = []
        for name in o.__slots__:
            v = getattr(o, name)
            fields.append(np.asarray(v).tobytes().hex() if isinstance(v, np.ndarray) else repr(v))
        h.update("|".join(fields).encode())
    h.update(repr(rng.bit_generator.state).encode())
