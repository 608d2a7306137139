"""Trajectory log: collects step records into arrays and writes ``trajectory.csv``."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from autonomy.frames import wrap_angle
from typing import Any

from sim.records import MissionInfo, MissionSummary, StepRecord

COLUMNS = (
    ["t_s", "mode"]
    + [f"true_{k}" for k in ("n_m", "e_m", "d_m", "roll_rad", "pitch_rad", "yaw_rad", "u_mps", "v_mps", "w_mps", "r_radps")]
    + [f"est_{k}" for k in ("n_m", "e_m", "d_m", "roll_rad", "pitch_rad", "yaw_rad", "u_mps", "v_mps", "w_mps")]
    + ["est_cov_nn_m2", "est_cov_ee_m2", "est_cov_dd_m2"]
    + ["cmd_speed_mps", "cmd_heading_rad", "cmd_altitude_m", "cmd_depth_m"]
    + [f"wrench_{k}" for k in ("X_N", "Y_N", "Z_N", "K_Nm", "M_Nm", "N_Nm")]
)


class TrajectoryLog:
    """Observer keeping the whole trajectory in memory (a few MB for an hour at 10 Hz)."""

    def __init__(self) -> None:
        self._rows: list[list[float]] = []
        self._modes: list[str] = []
        self._thrusters: list[NDArray] = []
        self._others: dict[str, list[NDArray]] = {}

    def on_start(self, info: MissionInfo) -> None:
        self._rows.clear()
        self._modes.clear()
        self._thrusters.clear()
        self._others = {}

    def on_step(self, r: StepRecord) -> None:
        tr, nav = r.truth, r.nav
        self._modes.append(r.mode)
        self._thrusters.append(np.asarray(r.thruster_cmd, dtype=float))
        for name, other in r.others.items():
            self._others.setdefault(name, []).append(other.pos_ned)
        self._rows.append(
            [r.t_s, *tr.pos_ned, *tr.rpy_rad, *tr.nu[:3], tr.nu[5],
             *nav.pos_ned, *nav.rpy_rad, *nav.vel_body_mps,
             *np.diag(nav.cov_pos_ned),
             r.setpoint_speed_mps, r.setpoint_heading_rad, r.setpoint_altitude_m, r.setpoint_depth_m,
             *r.wrench_body]
        )

    def on_message(self, name: str, msg: Any) -> None:
        pass

    def on_end(self, summary: MissionSummary) -> None:
        pass

    # -- derived quantities --------------------------------------------------------
    @property
    def table(self) -> NDArray[np.float64]:
        """(n, len(COLUMNS) - 1) numeric table (mode column excluded)."""
        return np.asarray(self._rows, dtype=float).reshape(-1, len(COLUMNS) - 1)

    def column(self, name: str) -> NDArray[np.float64]:
        idx = COLUMNS.index(name)
        return self.table[:, idx if idx == 0 else idx - 1]

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
        """Extra vehicle name -> its (n, 3) true NED path, m."""
        return {name: np.asarray(p, dtype=float).reshape(-1, 3) for name, p in self._others.items()}

    def distance_travelled_m(self) -> float:
        p = self.true_pos_ned
        return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=1))) if len(p) > 1 else 0.0

    def horizontal_error_m(self) -> NDArray[np.float64]:
        return np.linalg.norm(self.true_pos_ned[:, :2] - self.est_pos_ned[:, :2], axis=1)

    def navigation_metrics(self) -> dict[str, float]:
        if not self._rows:
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
        n_thr = len(self._thrusters[0]) if self._thrusters else 0
        header = COLUMNS + [f"thruster_{i}" for i in range(n_thr)]
        with open(path, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(header)
            for row, mode, thr in zip(self._rows, self._modes, self._thrusters):
                w.writerow([f"{row[0]:.3f}", mode, *(f"{v:.6g}" for v in row[1:]), *(f"{v:.4f}" for v in thr)])
