"""Trajectory log: spooled blocks give the same table and CSV as one block, memory stays flat."""

from __future__ import annotations

import csv
import tracemalloc

import numpy as np

from autonomy.frames import rot_from_euler
from autonomy.messages import NavEstimate
from sim.outputs.trajectory_log import COLUMNS, TrajectoryLog
from sim.events.records import StepRecord
from sim.dynamics.truth import VehicleTruth

MODES = ("idle", "dive", "survey")


def _records(n: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    for k in range(n):
        rpy = rng.uniform(-1.0, 1.0, 3)
        truth = VehicleTruth(t_s=0.1 * k, pos_ned=rng.normal(size=3) * 50, R_nb=rot_from_euler(*rpy), rpy_rad=rpy,
                             nu=rng.normal(size=6), nu_dot=np.zeros(6), current_ned=np.zeros(3))
        cov = np.diag(rng.uniform(0.0, 2.0, 3))
        nav = NavEstimate(t_s=0.1 * k, pos_ned=rng.normal(size=3), rpy_rad=rng.normal(size=3),
                          vel_body_mps=rng.normal(size=3), rate_body_radps=np.zeros(3), cov_pos_ned=cov)
        yield StepRecord(t_s=0.1 * k, truth=truth, nav=nav, setpoint_speed_mps=0.5, setpoint_heading_rad=float(k),
                         setpoint_altitude_m=float("nan") if k % 2 else 2.0, setpoint_depth_m=float("nan"),
                         wrench_body=rng.normal(size=6), thruster_cmd=rng.uniform(-1, 1, 4), mode=MODES[k // 40 % 3])


def _logged(block_rows: int, n: int) -> tuple[TrajectoryLog, list[StepRecord]]:
    log, recs = TrajectoryLog(block_rows=block_rows), list(_records(n))
    log.on_start(None)
    for r in recs:
        log.on_step(r)
    return log, recs


def test_spooled_blocks_give_the_rows_logged(tmp_path):
    small, recs = _logged(16, 103)  # six full blocks on disk, seven rows in memory
    one, _ = _logged(1000, 103)
    assert len(small) == len(one) == 103
    np.testing.assert_array_equal(small.table, one.table)
    np.testing.assert_array_equal(small.column("true_e_m"), [r.truth.pos_ned[1] for r in recs])
    np.testing.assert_array_equal(small.column("est_cov_dd_m2"), [r.nav.cov_pos_ned[2, 2] for r in recs])
    small.write_csv(tmp_path / "a.csv")
    one.write_csv(tmp_path / "b.csv")
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    rows = list(csv.reader(open(tmp_path / "a.csv")))
    assert rows[0] == COLUMNS + [f"thruster_{i}" for i in range(4)]
    assert [r[1] for r in rows[1:]] == [r.mode for r in recs]
    assert float(rows[50][COLUMNS.index("true_n_m")]) == float(f"{recs[49].truth.pos_ned[0]:.6g}")
    assert rows[-1][-1] == f"{recs[-1].thruster_cmd[-1]:.4f}"


def test_restart_forgets_the_previous_run():
    log, _ = _logged(16, 40)
    log.on_start(None)
    assert len(log) == 0 and log.table.shape == (0, len(COLUMNS) - 1)


def test_memory_is_flat_once_blocks_spool():
    recs = list(_records(200))
    log = TrajectoryLog(block_rows=256)
    log.on_start(None)
    tracemalloc.start()
    for k in range(300):
        log.on_step(recs[k % 200])
    before = tracemalloc.get_traced_memory()[0]
    for k in range(5000):
        log.on_step(recs[k % 200])
    grown = tracemalloc.get_traced_memory()[0] - before
    tracemalloc.stop()
    assert len(log) == 5300
    assert grown < 50_000  # a list of rows would hold ~1.5 kB per row, ~7 MB here
