"""Trajectory log: collects step records in float64 blocks (spooled to a temporary file) and writes
``trajectory.csv``."""

from __future__ import annotations

import csv
import tempfile
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import wrap_angle
from typing import Any

from sim.events.records import MissionInfo, MissionSummary, ObserverBase, StepRecord

COLUMNS = (
    ["t_s", "mode"]
    + [f"true_{k}" for k in ("n_m", "e_m", "d_m", "roll_rad", "pitch_rad", "yaw_rad", "u_mps", "v_mps", "w_mps", "r_radps")]
    + [f"est_{k}" for k in ("n_m", "e_m", "d_m", "roll_rad", "pitch_rad", "yaw_rad", "u_mps", "v_mps", "w_mps")]
    + ["est_cov_nn_m2", "est_cov_ee_m2", "est_cov_dd_m2"]
    + ["cmd_speed_mps", "cmd_heading_rad", "cmd_altitude_m", "cmd_depth_m"]
    + [f"wrench_{k}" for k in ("X_N", "Y_N", "Z_N", "K_Nm", "M_Nm", "N_Nm")]
)


#: Sampling of the extra vehicles' paths kept for the map, s.
OTHERS_EVERY_S = 1.0

class TrajectoryLog(ObserverBase):
    """Observer logging the trajectory at the autonomy rate, with memory flat over the mission.

    Each step is one float64 row (the numeric :data:`COLUMNS`, a mode code, the thruster
    commands) in a block of ``block_rows`` rows; full blocks are appended to an unnamed
    temporary file (``spool_dir``, default the system's temporary folder), so a 24 h
    mission at 10 Hz keeps about 1.4 MB in memory and spools about 300 MB to disk. Columns and
    ``trajectory.csv`` are read back block by block.
    """

    sonar_frames = False  # ignores the sonar's renders (the pipelined loop need not ship them)
    sonar_truth = False  # nor their ground truth (the sonar need not compute it)

    def __init__(self, *, block_rows: int = 4096, spool_dir: str | Path | None = None) -> None:
        self.block_rows = int(block_rows)
        self._spool_dir = spool_dir
        self._spool: Any = None  # temporary file of full blocks (created at the first one)
        self._n_spooled = 0
        self._block: NDArray[np.float64] | None = None
        self._n_block = 0
        self._width = 0
        self._mode_names: list[str] = []
        self._mode_code: dict[str, int] = {}
        self._others: dict[str, list[tuple[float, ...]]] = {}  # extra vehicles' path, one point a second
        self._others_next_s = 0.0

    def on_start(self, info: MissionInfo) -> None:
        if self._spool is not None:
            self._spool.close()
        self._spool, self._n_spooled, self._block, self._n_block = None, 0, None, 0
        self._mode_names.clear()
        self._mode_code.clear()
        self._others, self._others_next_s = {}, 0.0

    def on_step(self, r: StepRecord) -> None:
        tr, nav = r.truth, r.nav
        if r.others and r.t_s >= self._others_next_s:
            self._others_next_s = r.t_s + OTHERS_EVERY_S
            for name, other in r.others.items():
                self._others.setdefault(name, []).append((r.t_s, *other.pos_ned.tolist()))
        if self._block is None:
            self._width = len(COLUMNS) + len(r.thruster_cmd)  # numeric columns, mode code, thrusters
            self._block = np.empty((self.block_rows, self._width))
        code = self._mode_code.get(r.mode)
        if code is None:
            code = self._mode_code[r.mode] = len(self._mode_names)
            self._mode_names.append(r.mode)
        cov = nav.cov_pos_ned
        self._block[self._n_block] = (
            r.t_s, *tr.pos_ned.tolist(), *tr.rpy_rad.tolist(), *tr.nu[:3].tolist(), float(tr.nu[5]),
            *nav.pos_ned.tolist(), *nav.rpy_rad.tolist(), *nav.vel_body_mps.tolist(),
            float(cov[0, 0]), float(cov[1, 1]), float(cov[2, 2]),
            r.setpoint_speed_mps, r.setpoint_heading_rad, r.setpoint_altitude_m, r.setpoint_depth_m,
            *r.wrench_body.tolist(), code, *np.asarray(r.thruster_cmd, dtype=float).tolist())
        self._n_block += 1
        if self._n_block == self.block_rows:
            if self._spool is None:
                self._spool = tempfile.TemporaryFile(prefix="auvsim-trajectory-", dir=self._spool_dir)
            self._spool.write(self._block.tobytes())
            self._n_spooled += self.block_rows
            self._n_block = 0

    def on_message(self, name: str, msg: Any) -> None:
        pass

    def on_end(self, summary: MissionSummary) -> None:
        pass

    def __len__(self) -> int:
        """Rows logged."""
        return self._n_spooled + self._n_block

    def _blocks(self, max_rows: int = 65536):
        """The logged rows in order, as (k, width) float64 arrays of at most ``max_rows``."""
        if self._n_spooled:
            self._spool.flush()
            self._spool.seek(0)
            left = self._n_spooled
            while left:
                k = min(left, max_rows)
                yield np.frombuffer(self._spool.read(k * self._width * 8)).reshape(k, self._width)
                left -= k
            self._spool.seek(0, 2)
        if self._n_block:
            yield self._block[:self._n_block]

    def _columns(self, index: int | slice) -> NDArray[np.float64]:
        parts = [b[:, index] for b in self._blocks()]
        if not parts:
            return np.zeros((0,) if isinstance(index, int) else (0, len(range(self._width)[index])))
        return np.concatenate(parts).copy()

    # -- derived quantities --------------------------------------------------------
    @property
    def table(self) -> NDArray[np.float64]:
        """(n, len(COLUMNS) - 1) numeric table (mode column excluded)."""
        return self._columns(slice(0, len(COLUMNS) - 1))

    def column(self, name: str) -> NDArray[np.float64]:
        """(n,) values of the numeric column ``name`` of :data:`COLUMNS`."""
        idx = COLUMNS.index(name)
        return self._columns(idx if idx == 0 else idx - 1)

    @property
    def t_s(self) -> NDArray[np.float64]:
        return self.column("t_s")

    @property
    def true_pos_ned(self) -> NDArray[np.float64]:
        return np.c_[self.column("true_n_m"), self.column("true_e_m"), self.column("true_d_m")]

    @property
    def est_pos_ned(self) -> NDArray[np.float64]:
        return np.c_[self.column("est_n_m"), self.column("est_e_m"), self.column("est_d_m")]

    def other_paths_ned(self) -> dict[str, NDArray[np.float64]]:
        """Extra vehicle name -> its (n, 3) true NED path, m, one point every ``OTHERS_EVERY_S``."""
        return {name: np.asarray(p, dtype=float).reshape(-1, 4)[:, 1:] for name, p in self._others.items()}

    def other_paths_t_s(self) -> NDArray[np.float64]:
        """(n,) times of the points of :meth:`other_paths_ned`, s."""
        first = next(iter(self._others.values()), [])
        return np.asarray([p[0] for p in first], dtype=float)

    def distance_travelled_m(self) -> float:
        p = self.true_pos_ned
        return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))) if len(p) > 1 else 0.0

    def horizontal_error_m(self) -> NDArray[np.float64]:
        return np.linalg.norm(self.true_pos_ned[:, :2] - self.est_pos_ned[:, :2], axis=1)

    def navigation_metrics(self) -> dict[str, float]:
        if not len(self):
            return {"final_position_error_m": float("nan"), "max_position_error_m": float("nan"),
                    "drift_percent_of_distance": float("nan")}
        err = np.linalg.norm(self.true_pos_ned - self.est_pos_ned, axis=1)
        dist = self.distance_travelled_m()
        yaw_err = wrap_angle(self.column("true_yaw_rad") - self.column("est_yaw_rad"))
        return {
            "final_position_error_m": float(err[-1]),
            "max_position_error_m": float(err.max()),
            "mean_position_error_m": float(err.mean()),
            "drift_percent_of_distance": float(100.0 * err[-1] / dist) if dist > 0 else 0.0,
            "max_yaw_error_deg": float(np.rad2deg(np.max(np.abs(yaw_err)))),
        }

    def write_csv(self, path: Path) -> None:
        """``trajectory.csv``: the header of :data:`COLUMNS` and ``thruster_<i>``, one row a step."""
        n_num = len(COLUMNS) - 1
        n_thr = self._width - len(COLUMNS) if len(self) else 0
        header = COLUMNS + [f"thruster_{i}" for i in range(n_thr)]
        names = self._mode_names
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(header)
            for block in self._blocks():
                for row in block.tolist():
                    w.writerow([f"{row[0]:.3f}", names[int(row[n_num])], *(f"{v:.6g}" for v in row[1:n_num]),
                                *(f"{v:.4f}" for v in row[n_num + 1:])])
