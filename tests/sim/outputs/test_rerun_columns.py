"""The recording's per-step series sent as columns: read back from the ``.rrd``, the same rows
(entity, sim_time, values) as logging each step with ``rr.log`` (an independent recording
written the row-wise way in the same mission), in chunks of bounded length."""

from __future__ import annotations

from collections import defaultdict

from sim.events.records import ObserverBase
import numpy as np
import pytest

from autonomy.frames import quat_from_rot
from scenarios import load_scenario
from sim.mission import Mission
from sim.outputs.rerun_columns import ScalarColumn, duration_ns
from sim.outputs.rerun_recording import RerunRecorder

rr = pytest.importorskip("rerun")
from rerun.chunk import RrdReader  # noqa: E402

SERIES = ("world/vehicle", "nav/horizontal_error_m", "nav/sigma_horizontal_m", "nav/depth_error_m")


class _RowWise(ObserverBase):
    """Logs the step series one ``rr.log`` per step (the row-wise reference)."""

    def __init__(self, path) -> None:
        self.rec = rr.RecordingStream("reference")
        self.path = path
        self.n_steps = 0

    def on_start(self, info) -> None:
        self.rec.save(self.path)

    def on_message(self, name, msg) -> None:
        pass

    def on_step(self, r) -> None:
        rec, tr, nav = self.rec, r.truth, r.nav
        self.n_steps += 1
        rec.set_time("sim_time", duration=r.t_s)
        w, x, y, z = quat_from_rot(tr.R_nb)
        rec.log("world/vehicle", rr.Transform3D(translation=tr.pos_ned, quaternion=[x, y, z, w]))
        rec.log("nav/horizontal_error_m", rr.Scalars(float(np.linalg.norm(tr.pos_ned[:2] - nav.pos_ned[:2]))))
        rec.log("nav/sigma_horizontal_m", rr.Scalars(float(np.sqrt(np.trace(nav.cov_pos_ned[:2, :2])))))
        rec.log("nav/depth_error_m", rr.Scalars(float(tr.pos_ned[2] - nav.pos_ned[2])))

    def on_end(self, summary) -> None:
        self.rec.flush()
        self.rec.disconnect()


def _rows(path) -> tuple[dict[str, dict[str, np.ndarray]], dict[str, list[int]]]:
    """Per entity: its ``sim_time`` (ns) and component columns sorted by time; and the row
    count of each of its chunks."""
    cols: dict[str, dict[str, list]] = defaultdict(lambda: defaultdict(list))
    sizes: dict[str, list[int]] = defaultdict(list)
    for ch in RrdReader(path).stream():
        ent = ch.entity_path.lstrip("/")
        if ent not in SERIES:
            continue
        sizes[ent].append(ch.num_rows)
        rb = ch.to_record_batch()
        for name in rb.schema.names:
            if name == "sim_time":
                cols[ent][name].append(rb.column(name).cast("int64").to_numpy())
            elif ":" in name:  # component columns
                cols[ent][name] += rb.column(name).to_pylist()
    out = {}
    for ent, c in cols.items():
        t = np.concatenate(c["sim_time"])
        order = np.argsort(t, kind="stable")
        out[ent] = {"sim_time": t[order], **{k: [v[i] for i in order] for k, v in c.items() if k != "sim_time"}}
    return out, sizes


def test_step_series_read_back_as_the_row_wise_log_in_bounded_chunks(tmp_path):
    scn = load_scenario("cssn_lawnmower", ["duration_s=12", "sensors.fls.enabled=false"])
    ref = _RowWise(tmp_path / "rows.rrd")
    rec = RerunRecorder(tmp_path / "columns.rrd", series_rows=25)
    Mission(scn, observers=[rec, ref]).run(progress=False)
    got, sizes = _rows(tmp_path / "columns.rrd")
    want, _ = _rows(tmp_path / "rows.rrd")
    n = ref.n_steps
    assert n > 100
    for ent in SERIES:
        assert len(got[ent]["sim_time"]) == n
        np.testing.assert_array_equal(got[ent]["sim_time"], want[ent]["sim_time"])
        comps = [k for k in want[ent] if k != "sim_time" and any(v is not None for v in want[ent][k])]
        assert comps, ent
        for k in comps:  # translation, quaternion or scalar: the same float values
            assert got[ent][k] == want[ent][k], (ent, k)
        assert max(sizes[ent]) <= 25 and sum(sizes[ent]) == n  # chunks of at most series_rows


def test_column_buffer_sends_when_full_and_at_the_end():
    class _Rec:
        def __init__(self) -> None:
            self.sent: list[tuple] = []

        def send_columns(self, entity, indexes, columns) -> None:
            self.sent.append((entity, indexes[0].as_arrow_array().cast("int64").to_pylist(),
                              list(columns)[0].as_arrow_array().to_pylist()))

    rec = _Rec()
    col = ScalarColumn("nav/x", capacity=3)
    for k in range(7):
        col.append(rec, rr, 0.1 * k, float(k))
    assert [len(s[1]) for s in rec.sent] == [3, 3] and len(col) == 1
    col.send(rec, rr)
    col.send(rec, rr)  # nothing left: no empty chunk
    assert [len(s[1]) for s in rec.sent] == [3, 3, 1]
    assert [t for s in rec.sent for t in s[1]] == [duration_ns(0.1 * k) for k in range(7)]
    assert duration_ns(0.3) == 300_000_000 and duration_ns(1e-9) == 1
    with pytest.raises(ValueError, match="capacity 0"):
        ScalarColumn("nav/x", capacity=0)
