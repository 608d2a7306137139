"""Side-scan tiles assembled onboard from pings and the navigation estimate.

Every ``tile_period_s`` seconds of pings (tile k holds the pings with ``t`` in
``((k - 1) T, k T]``) the assembler emits a :class:`SssTileImage`: the port and starboard
waterfalls (one row per ping; ground range when the pings carry ground-range lines, else
slant range) and, per row, the transducer's pose from the navigation estimate moved to the
ping's own time (:func:`autonomy.navigation.pose_at.pose_at`: the filter's time is its last
IMU message, up to an IMU period from the ping; held, the rows would be unevenly spaced). The tile
frame is the vehicle frame at the tile's last ping (paper 003, Section V: along-track
forward, across-track starboard, m): :meth:`SssTileImage.to_tile_frame` maps a pixel there
through its row's pose, so turns within a tile are followed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from autonomy.messages import NavEstimate, SssPing
from autonomy.navigation.pose_at import pose_at

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SssTileImage:
    """One tile pair.

    Attributes:
        index: tile number k (1-based; the tile ends at ``k tile_period_s``).
        t_s: time of its last ping, s.
        image: (2, n_pings, n_bins) uint8, side 0 port, 1 starboard; column j is range
            ``(j + 0.5) bin_size_m`` from nadir (ground) or the transducer (slant).
        ground_range: whether columns are ground range (else slant range).
        bin_size_m: column size, m.
        altitude_m: (n_pings,) altitude of each ping, m.
        pos_ne: (n_pings, 2) transducer north, east at each ping (navigation estimate), m.
        heading_rad: (n_pings,) heading at each ping (NED yaw).
        ping_t_s: (n_pings,) ping times, s.
    """

    index: int
    t_s: float
    image: NDArray[np.uint8]
    ground_range: bool
    bin_size_m: float
    altitude_m: FloatArray
    pos_ne: FloatArray
    heading_rad: FloatArray
    ping_t_s: FloatArray

    def ground_range_m(self, col: NDArray, row: NDArray) -> FloatArray:
        """Ground range (m) of fractional columns ``col`` at rows ``row`` (same shape)."""
        r = (np.asarray(col, dtype=float) + 0.5) * self.bin_size_m
        if self.ground_range:
            return r
        h = self.altitude_m[np.clip(np.asarray(row, dtype=int), 0, len(self.altitude_m) - 1)]
        return np.sqrt(np.maximum(r * r - np.nan_to_num(h) ** 2, 0.0))

    def to_ned(self, side: NDArray, row: NDArray, col: NDArray) -> FloatArray:
        """(k, 2) north, east (m, navigation frame) of pixels (side 0/1, fractional row, column)."""
        side = np.asarray(side)
        row = np.asarray(row, dtype=float)
        idx = np.arange(len(self.ping_t_s))
        n = np.interp(row, idx, self.pos_ne[:, 0])
        e = np.interp(row, idx, self.pos_ne[:, 1])
        psi = np.interp(row, idx, np.unwrap(self.heading_rad))
        g = self.ground_range_m(col, np.rint(row)) * np.where(side == 1, 1.0, -1.0)
        return np.column_stack([n - g * np.sin(psi), e + g * np.cos(psi)])

    def to_tile_frame(self, pos_ne: FloatArray) -> FloatArray:
        """(k, 2) NED positions -> the tile frame (along forward, across starboard) m, at the
        last ping's pose."""
        d = np.asarray(pos_ne, dtype=float).reshape(-1, 2) - self.pos_ne[-1]
        c, s = np.cos(self.heading_rad[-1]), np.sin(self.heading_rad[-1])
        return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])


class SssTileAssembler:
    """Collects pings with their navigation poses and cuts a tile every ``tile_period_s``.

    Args:
        tile_period_s: T, s (> 0).

    Raises:
        ValueError: a non-positive period.
    """

    def __init__(self, tile_period_s: float) -> None:
        if not tile_period_s > 0.0:
            raise ValueError(f"tile_period_s must be > 0, got {tile_period_s}")
        self.period_s = float(tile_period_s)
        self.reset()

    def reset(self) -> None:
        self._rows: list[tuple[float, NDArray[np.uint8], float, FloatArray, float]] = []
        self._index = 1
        self._ground: bool | None = None
        self._bin_size_m = 0.0

    def add(self, ping: SssPing, nav: NavEstimate) -> SssTileImage | None:
        """Add a ping with the navigation estimate ``nav`` (of any time near the ping's: it
        is moved to ``ping.t_s`` with its velocity and rates); returns the tile it closes,
        else None.

        The ping with ``t > k T`` closes tile k (made of the pings before it) and opens tile
        k + 1; a tile with no ping (a gap longer than T) is skipped.
        """
        out = None
        if ping.t_s > self._index * self.period_s + 1e-9:
            out = self._cut() if self._rows else None
            self._index = int(np.floor(ping.t_s / self.period_s - 1e-9)) + 1
        lines = ping.ground_lines_u8 if ping.ground_lines_u8 is not None else ping.lines_u8
        self._ground = ping.ground_lines_u8 is not None
        self._bin_size_m = float(ping.bin_size_m)
        pos_ned, rpy = pose_at(nav, ping.t_s)
        c, s = np.cos(rpy[2]), np.sin(rpy[2])
        m = np.asarray(ping.mount_pos_body_m, dtype=float)
        pos = pos_ned[:2] + np.array([c * m[0] - s * m[1], s * m[0] + c * m[1]])
        self._rows.append((float(ping.t_s), np.asarray(lines, dtype=np.uint8), float(ping.altitude_m), pos,
                           float(rpy[2])))
        return out

    def _cut(self) -> SssTileImage:
        t, lines, alt, pos, psi = zip(*self._rows)
        self._rows = []
        return SssTileImage(index=self._index, t_s=t[-1], image=np.stack(lines, axis=1), ground_range=bool(self._ground),
                            bin_size_m=self._bin_size_m, altitude_m=np.array(alt), pos_ne=np.array(pos),
                            heading_rad=np.array(psi), ping_t_s=np.array(t))
