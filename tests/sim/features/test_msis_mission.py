"""Scanning-sonar position fixes in the loop: the EKF update and the pool scenario."""

from __future__ import annotations

from sim.events.records import ObserverBase
import numpy as np
import pytest

from autonomy.messages import PositionFixMsg
from autonomy.navigation import NavigationFilter
from autonomy.navigation.config import NavigationConfig
from scenarios import load_scenario
from sim.mission import Mission
from sim.features import MsisLocalizationFeature
from sim.sensors.nav_noise import nav_noise_model


def test_position_fix_is_the_kalman_update_of_the_horizontal_position():
    f = NavigationFilter(NavigationConfig(initial_pos_sigma_m=2.0), np.zeros(3), 0.0, nav_noise_model())
    P0 = f.covariance[:2, :2]
    R = np.array([[0.25, 0.05], [0.05, 0.16]])
    z = np.array([1.0, -0.5])
    assert f.on_position_fix(PositionFixMsg(0.0, z, R))
    K = P0 @ np.linalg.inv(P0 + R)  # position block only: the prior has no cross terms
    assert np.allclose(f.state[:2], K @ z)
    assert np.allclose(f.covariance[:2, :2], (np.eye(2) - K) @ P0)
    dr = NavigationFilter(NavigationConfig(mode="dead_reckoning"), np.zeros(3), 0.0, nav_noise_model())
    assert not dr.on_position_fix(PositionFixMsg(0.0, z, R))


def test_pool_circle_fixes_reach_the_filter_and_lie_near_the_truth():
    scn = load_scenario("pool_circular", ["duration_s=40"])
    mission = Mission(scn)
    obs = mission.feature(MsisLocalizationFeature).error_observer()
    truth_at: dict[float, np.ndarray] = {}

    class _Truth(ObserverBase):
        def on_start(self, info): pass
        def on_message(self, name, msg): pass
        def on_end(self, summary): pass
        def on_step(self, rec): truth_at[round(rec.t_s, 3)] = rec.truth.pos_ned[:2].copy()

    mission.observers += [obs, _Truth()]
    mission.run(progress=False)
    assert mission.summary().messages_delivered["msis"] == pytest.approx(40 / scn.sensors.msis.ping_duration_s, abs=3)
    assert len(obs.fixes) >= 3
    times = np.array(sorted(truth_at))
    for fix in obs.fixes:
        t = times[np.argmin(np.abs(times - fix.t_s))]
        err = np.linalg.norm(fix.pos_ne_m - truth_at[t])
        assert err < 0.3 and err < 4.0 * np.sqrt(np.trace(fix.cov_ne_m2))
    assert obs.err_fused_m[-1] < 0.3
