"""The sonar buffer of [P002] section 3.1: echo points of recent pings, motion-compensated.

Each ping gives its echo ranges above an intensity threshold (the first strong return's leading
edge or its centre, or all local peaks); each is placed where the head saw it, with the navigation estimate of the ping
time (moved from the estimate's own time with its velocity and body rates,
:func:`autonomy.navigation.pose_at.pose_at`): body point
``mount + R_bs Rz(angle) [r, 0, 0]`` (the head frame of :mod:`autonomy.sonar_frame` turned by
the head angle), then ``pos + R(rpy) p_body`` in NED. Points older than ``max_age_s`` age out.
Stored in the navigation frame, the points are the vehicle-centred consistent local map of the
paper expressed once: :meth:`SonarBuffer.points_body` gives them about the current pose.
Motion during a sweep is thus removed as well as the navigation estimate allows.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import rot_from_euler, rot_z
from autonomy.messages import MsisPing, NavEstimate
from autonomy.navigation.pose_at import pose_at
from autonomy.sonar_frame import sonar_to_body_rotation

FloatArray = NDArray[np.float64]


def echo_ranges_m(ping: MsisPing, threshold_u8: int, min_range_m: float, mode: str = "first",
                  min_gap_m: float = 0.3) -> FloatArray:
    """Slant ranges (m, sample centres) of a ping's echoes.

    ``first``: the first sample at or above ``threshold_u8`` beyond ``min_range_m`` (at most
    one); ``first_centre``: the intensity-weighted centre (weights ``x - threshold + 1``) of the
    first echo, the samples at or above the threshold from that first one on, up to a gap of
    ``min_gap_m`` (at most one). On a wall seen at incidence ``a`` the beam of half width ``b``
    spreads the echo over ``d / cos(a - b)`` to ``d / cos(a + b)``: the leading edge comes from
    the beam's near edge (short by up to ~5 % at 70 deg for a 2 deg beam, which bends a wall
    seen obliquely towards the vehicle and tilts it), the centre from about the beam axis;
    ``peaks``: every local maximum at or above it, at least ``min_gap_m`` apart (the
    strongest kept first).

    Raises:
        ValueError: an unknown mode.
    """
    x = ping.intensity
    dr = ping.sample_spacing_m
    k0 = int(np.ceil(min_range_m / dr))
    if mode in ("first", "first_centre"):
        above = np.flatnonzero(x[k0:] >= threshold_u8)
        if not above.size:
            return np.zeros(0)
        k1 = int(above[0]) + k0
        if mode == "first":
            return np.array([k1 + 0.5]) * dr
        gap = max(int(round(min_gap_m / dr)), 1)
        # the first echo: samples at or above the threshold, gaps shorter than min_gap_m
        idx = above + k0
        breaks = np.flatnonzero(np.diff(idx) > gap)
        end = int(idx[breaks[0]]) if breaks.size else int(idx[-1])
        seg = np.arange(k1, end + 1)
        w = np.maximum(x[seg].astype(float) - threshold_u8 + 1.0, 0.0)
        return np.array([float(w @ (seg + 0.5)) / float(w.sum())]) * dr
    if mode != "peaks":
        raise ValueError(f"mode must be 'first', 'first_centre' or 'peaks', got {mode!r}")
    xi = x.astype(np.int16)
    k = np.arange(max(k0, 1), len(x) - 1)
    cand = k[(xi[k] >= threshold_u8) & (xi[k] >= xi[k - 1]) & (xi[k] > xi[k + 1])]
    gap = max(int(round(min_gap_m / dr)), 1)
    kept: list[int] = []
    for c in cand[np.argsort(-xi[cand], kind="stable")]:
        if all(abs(int(c) - j) >= gap for j in kept):
            kept.append(int(c))
    return (np.sort(np.array(kept, dtype=float)) + 0.5) * dr


class SonarBuffer:
    """Echo points of recent pings in the navigation (NED) frame.

    Args:
        threshold_u8: echo threshold on the raw samples.
        min_range_m: samples nearer than this are ignored (ringing, the vehicle's own frame).
        max_age_s: points older than this age out.
        mode: ``first``, ``first_centre`` or ``peaks`` (:func:`echo_ranges_m`).
    """

    def __init__(self, threshold_u8: int = 200, min_range_m: float = 0.75, max_age_s: float = 30.0,
                 mode: str = "first") -> None:
        self.threshold_u8 = int(threshold_u8)
        self.min_range_m = float(min_range_m)
        self.max_age_s = float(max_age_s)
        self.mode = mode
        self._pts: deque[tuple[float, float, float, int]] = deque()  # (t_s, north, east, ping index)
        self._n_pings = 0
        self._R_head: dict[tuple, FloatArray] = {}

    def __len__(self) -> int:
        return len(self._pts)

    def clear(self) -> None:
        self._pts.clear()

    def add_ping(self, ping: MsisPing, nav: NavEstimate) -> int:
        """Add a ping's echoes with the navigation estimate ``nav`` (extrapolated to the ping
        time); age out old points. Returns the number of points added."""
        self._n_pings += 1
        ranges = echo_ranges_m(ping, self.threshold_u8, self.min_range_m, self.mode)
        self.age_out(ping.t_s)
        if ranges.size == 0:
            return 0
        key = (float(ping.angle_grad), *np.asarray(ping.mount_rpy_rad, dtype=float).tolist())
        R_bh = self._R_head.get(key)
        if R_bh is None:
            R_bh = sonar_to_body_rotation(ping.mount_rpy_rad) @ rot_z(ping.angle_rad)
            self._R_head[key] = R_bh
        pos, rpy = pose_at(nav, ping.t_s)
        R_nb = rot_from_euler(*rpy)
        p_body = np.asarray(ping.mount_pos_body_m)[None, :] + ranges[:, None] * R_bh[:, 0][None, :]
        p_ned = pos[None, :] + p_body @ R_nb.T
        for q in p_ned:
            self._pts.append((float(ping.t_s), float(q[0]), float(q[1]), self._n_pings))
        return len(ranges)

    def age_out(self, t_s: float) -> None:
        while self._pts and self._pts[0][0] < t_s - self.max_age_s:
            self._pts.popleft()

    def points_ne(self) -> FloatArray:
        """(N, 2) north, east of the points in ping order, m."""
        if not self._pts:
            return np.zeros((0, 2))
        return np.array([(p[1], p[2]) for p in self._pts])

    def times_s(self) -> FloatArray:
        """(N,) ping times of the points, s."""
        return np.array([p[0] for p in self._pts])

    def points_body(self, nav: NavEstimate) -> FloatArray:
        """(N, 2) the points about the current pose: forward, starboard of the body origin
        (horizontal, heading only), m."""
        d = self.points_ne() - np.asarray(nav.pos_ned[:2])[None, :]
        c, s = np.cos(nav.rpy_rad[2]), np.sin(nav.rpy_rad[2])
        return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
