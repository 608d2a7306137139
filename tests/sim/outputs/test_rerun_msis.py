"""The rerun recording of a scanning-sonar mission: every ping logged along its true beam,
the scan image re-logged as it builds up, and the features of each position fix."""

from __future__ import annotations


from sim.events.records import ObserverBase
import numpy as np
import pytest

from scenarios import load_scenario
from sim.mission import Mission
from sim.outputs.rerun_recording import RerunRecorder
from sim.sensors.msis import MsisRender
from tests.support import FakeRerunStream, image_strips

rr = pytest.importorskip("rerun")


class _Pings(ObserverBase):
    def __init__(self) -> None:
        self.renders: list[MsisRender] = []
        self.fixes: list = []
        self.nav_error: dict[float, np.ndarray] = {}  # t_s -> (2,) estimate - truth, m

    def on_start(self, info): pass

    def on_step(self, rec):
        self.nav_error[round(rec.t_s, 3)] = rec.nav.pos_ned[:2] - rec.truth.pos_ned[:2]

    def error_at(self, t_s: float) -> np.ndarray:
        """Navigation error (2,) of the last step at or before ``t_s``, m."""
        return self.nav_error[max(t for t in self.nav_error if t <= t_s + 1e-6)]
    def on_end(self, summary): pass

    def on_message(self, name, msg):
        if isinstance(msg, MsisRender):
            self.renders.append(msg)
        elif type(msg).__name__ == "PositionFixMsg":
            self.fixes.append(msg)


def _positions(arch) -> np.ndarray:
    return np.asarray(arch.positions.as_arrow_array().to_pylist(), dtype=float).reshape(-1, 3)


def _record(scenario: str, duration_s: float, tmp_path):
    scn = load_scenario(scenario, [f"duration_s={duration_s}"])
    fake = RerunRecorder(tmp_path / "fake.rrd")
    fake._rec = FakeRerunStream()
    real = RerunRecorder(tmp_path / "real.rrd")
    pings = _Pings()
    mission = Mission(scn, observers=[fake, real, pings])
    mission.run(progress=False)
    return mission, fake._rec.logs, pings, tmp_path / "real.rrd"


def test_pool_recording_logs_every_ping_along_its_beam_and_the_fitted_circle(tmp_path):
    mission, logs, pings, rrd = _record("pool_circular", 12.0, tmp_path)
    n = mission.summary().messages_delivered["msis"]
    assert n == len(pings.renders) > 400
    assert len(logs["world/msis/msis/ping"]) == n and len(logs["world/msis/msis/beam"]) == n
    assert len(logs["sonar/msis/msis/scan"]) == -(-n // 10)
    assert rrd.stat().st_size > 100_000  # the real stream wrote the pings too

    near_wall = 0
    for render, arch in zip(pings.renders, logs["world/msis/msis/ping"]):
        if isinstance(arch, rr.Clear):
            assert render.ping.intensity.max() < 80
            continue
        p = _positions(arch)
        head, u = render.truth.pos_ned, render.truth.R_ns[:, 0]
        d = p - head
        r = d @ u
        # every point on the ping's own beam, within its range
        assert np.allclose(d, r[:, None] * u[None, :], atol=1e-4)  # rerun keeps float32
        assert np.all((r > 0) & (r <= len(render.ping.intensity) * render.ping.sample_spacing_m))
        # the strongest raw sample, placed independently, is among the logged points
        k = int(np.argmax(render.ping.intensity))
        q = head + (k + 0.5) * render.ping.sample_spacing_m * u
        assert np.min(np.linalg.norm(p - q, axis=1)) <= 0.5 * len(render.ping.intensity) / 200 * \
            render.ping.sample_spacing_m + 1e-4
        near_wall += abs(np.hypot(q[0], q[1]) - 6.0) < 0.3
    assert near_wall >= 0.8 * n  # most pings' strongest echo is the 6 m pool wall

    assert len(pings.fixes) >= 1 and len(logs["world/msis/msis/fix/circle"]) == len(pings.fixes)
    # features are in the navigation frame: less the navigation error they lie on the true wall
    err = pings.error_at(pings.fixes[-1].t_s)
    circle = image_strips(logs["world/msis/msis/fix/circle"][-1])[0][:, :2] - err
    assert np.allclose(np.hypot(circle[:, 0], circle[:, 1]), 6.0, atol=0.3)
    pts = _positions(logs["world/msis/msis/fix/points"][-1])[:, :2] - err
    assert len(pts) == len(pings.fixes[-1].points_ne_m)
    assert np.median(np.abs(np.hypot(pts[:, 0], pts[:, 1]) - 6.0)) < 0.2
    pos = _positions(logs["world/msis/msis/fix/position"][-1])[0, :2]
    assert np.allclose(pos, pings.fixes[-1].pos_ne_m, atol=1e-4)


def test_tank_recording_logs_wall_segments_with_their_95_percent_bands(tmp_path):
    mission, logs, pings, _ = _record("tank_rectangular", 20.0, tmp_path)
    assert len(logs["world/msis/msis/ping"]) == mission.summary().messages_delivered["msis"]
    assert logs["world/msis/msis/fix/segments"], "no wall fix in 20 s"
    assert not logs["world/msis/msis/fix/circle"]
    for seg_arch, band_arch, fix in zip(logs["world/msis/msis/fix/segments"], logs["world/msis/msis/fix/segments_95"],
                                        pings.fixes):
        segs = image_strips(seg_arch)
        bands = image_strips(band_arch)
        assert len(segs) == len(fix.segments_ne_m) and len(bands) == 2 * len(segs)
        on_wall = 0
        err = pings.error_at(fix.t_s)
        for i, s in enumerate(segs):
            ne = s[:, :2]
            assert np.allclose(ne, fix.segments_ne_m[i], atol=1e-4)
            ne_true = ne - err
            # distance of both end points to the nearest true wall (north +-10 m, east +-5 m)
            dist = np.minimum(np.abs(np.abs(ne_true[:, 0]) - 10.0), np.abs(np.abs(ne_true[:, 1]) - 5.0))
            on_wall += bool(np.all(dist < 0.3))
            t = (ne[1] - ne[0]) / np.linalg.norm(ne[1] - ne[0])
            for b in (bands[i][:, :2], bands[len(segs) + i][:, :2]):
                off = b - ne
                assert np.allclose(off @ t, 0.0, atol=1e-4)  # rerun keeps float32  # parallel, offset along the normal
                assert np.allclose(np.linalg.norm(off, axis=1), fix.segments_rho95_m[i], atol=1e-4)
        assert on_wall >= 2
