"""Regulator bubble plumes against analytic rise and drift: each breath leaves the regulator
where the diver was, rises at its speed, is carried by the current (constant or varying)
and briefly by the diver's wake, spreads horizontally, and a swimming diver leaves a trail
behind and above."""

from __future__ import annotations

import math

import numpy as np
import pytest

from scenarios.config.movers import BubbleConfig, MoverConfig
from scenarios.config.world import CurrentConfig
from scenarios.schema import Scenario
from sim.dynamics.current import OceanCurrent
from sim.scene.physics import Physics
from sim.scene.target_motion import BubblePlumes, ManoeuvreTrajectory, WaterDrift

U_MPS, START = 0.3, np.array([0.0, 0.0, 8.0])
HOVERING_DIVER = dict(name="diver", kind="diver", initial_pos_ned=(6.0, 0.0, 5.0), surge_mps=0.0, surge_sigma_mps=0.0,
                      course_rate_sigma_dps=0.0, heave_sigma_mps=0.0, bubbles={"enabled": True})


def _straight_diver(duration_s: float = 120.0) -> ManoeuvreTrajectory:
    cfg = MoverConfig(name="d", initial_pos_ned=tuple(START), initial_course_deg=90.0, surge_mps=U_MPS,
                      surge_sigma_mps=0.0, course_rate_sigma_dps=0.0, heave_sigma_mps=0.0, leash_radius_m=1000.0)
    return ManoeuvreTrajectory(cfg, np.random.default_rng(0), duration_s)


def _centroids(plume: BubblePlumes, t_s: float) -> dict[int, np.ndarray]:
    """Release index -> (3,) centroid of that breath's live bubbles at t_s."""
    pos, alive = plume.positions_at(t_s)
    m = plume.cfg.per_breath
    out = {}
    for k in np.nonzero((plume.release_t_s <= t_s) & (plume.release_t_s > t_s - plume.cfg.lifetime_s))[0]:
        sl = slice((k % plume.n_slots) * m, (k % plume.n_slots + 1) * m)
        if alive[sl].all():
            out[int(k)] = pos[sl].mean(axis=0)
    return out


def test_breath_centroids_follow_rise_current_and_wake():
    """Diver swimming east at 0.3 m/s in a 0.1 N / -0.15 E current: each breath's centroid is
    at the regulator where the diver was at release (0.8 m ahead, 0.25 m up), risen by
    ``rise x age``, carried ``current x age`` and ``f v_rel tau (1 - exp(-age / tau))``."""
    cur = np.array([0.1, -0.15, 0.0])
    cfg = BubbleConfig(per_breath=20, rise_speed_sigma_mps=0.0, dispersion_mps=0.0, lifetime_s=12.0)
    plume = BubblePlumes(cfg, _straight_diver(), np.random.default_rng(3), 120.0, drift=WaterDrift(cur))
    gaps = np.diff(plume.release_t_s)
    assert 0.6 * 4.5 - 1e-9 <= gaps.min() and gaps.max() <= 1.4 * 4.5 + 1e-9
    assert abs(gaps.mean() - 4.5) < 0.2 and gaps.std() > 0.2  # every breath, about 4.5 s apart, not a metronome
    v_rel = np.array([0.0, U_MPS, 0.0]) - cur  # through the water
    checked = 0
    for t in (31.0, 47.3, 60.0):
        for k, c in _centroids(plume, t).items():
            tk = plume.release_t_s[k]
            age = t - tk
            reg = START + np.array([0.0, U_MPS * tk + 0.8, -0.25])
            wake = cfg.wake_fraction * cfg.wake_decay_s * (1.0 - math.exp(-age / cfg.wake_decay_s)) * v_rel
            expect = reg + np.array([0.0, 0.0, -cfg.rise_speed_mps * age]) + cur * age + np.r_[wake[:2], 0.0]
            np.testing.assert_allclose(c, expect, atol=0.05)  # 20 bubbles scattered 5 cm about the regulator
            checked += 1
    assert checked >= 6


def test_swimming_diver_leaves_a_trail_behind_and_above():
    """Still water: breaths stay where they were released while the diver swims on, so older
    breaths are further behind the diver's head (by ``u x`` their age, less the wake's push)
    and higher."""
    cfg = BubbleConfig(per_breath=10, rise_speed_sigma_mps=0.0, dispersion_mps=0.0, wake_fraction=0.0)
    traj = _straight_diver()
    plume = BubblePlumes(cfg, traj, np.random.default_rng(4), 120.0)
    t = 50.0
    head_e = traj.pose_at(t)[0][1] + 0.8
    cents = _centroids(plume, t)
    assert len(cents) >= 2
    for k, c in cents.items():
        age = t - plume.release_t_s[k]
        assert c[1] == pytest.approx(head_e - U_MPS * age, abs=0.05)  # behind
        assert c[2] == pytest.approx(START[2] - 0.25 - cfg.rise_speed_mps * age, abs=0.05)  # above


def test_breath_cluster_spreads_linearly_with_age():
    """Horizontal spread: per-axis variance about the breath's centroid is
    ``0.05^2 + (dispersion x age)^2`` (release scatter plus spread velocity), pooled over breaths."""
    cfg = BubbleConfig(per_breath=20, dispersion_mps=0.06, rise_speed_sigma_mps=0.0, lifetime_s=12.0)
    plume = BubblePlumes(cfg, _straight_diver(400.0), np.random.default_rng(5), 400.0)
    m = cfg.per_breath
    for age in (1.0, 4.0, 8.0):
        var = []
        for k in range(5, 80):
            pos, alive = plume.positions_at(plume.release_t_s[k] + age)
            sl = slice((k % plume.n_slots) * m, (k % plume.n_slots + 1) * m)
            xy = pos[sl, :2]
            var.append(((xy - xy.mean(axis=0)) ** 2).sum(axis=0) / (m - 1))
        v = np.mean(var)
        assert v == pytest.approx(0.05**2 + (0.06 * age) ** 2, rel=0.15)


def test_water_drift_integrates_a_varying_current():
    """A Gauss-Markov current recorded at every 0.01 s step: the displacement equals the
    sum of velocity x step (independent cumulative sum), between steps too, and a clock reset
    starts again from zero."""
    cfg = CurrentConfig(velocity_ned_mps=(0.1, -0.05, 0.0), gauss_markov_sigma_mps=0.05, gauss_markov_tau_s=5.0)
    cur = OceanCurrent(cfg, np.random.default_rng(7))
    drift = WaterDrift(cur.mean_ned)
    dt, n = 0.01, 3000
    vel = np.empty((n, 3))
    for i in range(n):
        vel[i] = cur.velocity_tuple
        drift.record(i * dt, cur.velocity_tuple)
        cur.step(dt)
    cum = np.vstack([np.zeros(3), np.cumsum(vel * dt, axis=0)])
    ts = np.arange(n) * dt
    np.testing.assert_allclose(drift.displacement_at(ts), cum[:-1], atol=1e-9)
    np.testing.assert_allclose(drift.displacement_at(12.345), cum[1234] + vel[1234] * 0.005, atol=1e-9)
    assert np.linalg.norm(cum[-1] - cur.mean_ned * n * dt) > 0.05  # the varying part matters
    drift.record(0.0, cur.mean_ned)
    np.testing.assert_allclose(drift.displacement_at(2.0), 2.0 * cur.mean_ned, atol=1e-12)


def test_physics_carries_the_bubbles_with_the_current():
    """In the MuJoCo scene, the same seed with and without a 0.2 m/s east current: every
    bubble alive in both is displaced east by 0.2 x its age (less the wake's share of the
    current), a hovering diver's plume leaves it downstream."""

    def run(current_e: float):
        scn = Scenario(name="plume", duration_s=20.0,
                       world={"seabed": {"depth_m": 30.0}, "movers": [HOVERING_DIVER],
                              "current": {"velocity_ned_mps": (0.0, current_e, 0.0)}},
                       vehicle={"model": "bluerov2_heavy", "initial_pos_ned": (0.0, 0.0, 5.0)})
        phys = Physics(scn)
        phys.reset(scn.vehicle.initial_pos_ned, (0.0, 0.0, 0.0))
        phys.advance(np.zeros(phys.params.n_thrusters), int(round(9.0 / phys.dt_s)))
        plume = phys.movers.plumes["diver"]
        ids = phys.movers._bubble_slots["diver"]
        return phys.t_s, phys.dt_s, plume, phys.data.mocap_pos[ids].copy(), plume.positions_at(phys.t_s)[1]

    t, dt, plume, still, alive0 = run(0.0)
    *_, moved, alive1 = run(0.2)
    both = alive0 & alive1
    assert both.sum() >= plume.cfg.per_breath
    m = plume.cfg.per_breath
    k_of_slot = {}
    for k in np.nonzero(plume.release_t_s <= t)[0]:
        k_of_slot[k % plume.n_slots] = k
    for i in np.nonzero(both)[0]:
        age = t - dt - plume.release_t_s[k_of_slot[i // m]]  # the mocap pose is set before the last step
        # the hovering diver moves through the water at -0.2 m/s: its wake pushes the breath upstream
        wake = plume.cfg.wake_fraction * plume.cfg.wake_decay_s * (1.0 - math.exp(-age / plume.cfg.wake_decay_s))
        expect_e = 0.2 * age - 0.2 * wake
        assert moved[i, 1] - still[i, 1] == pytest.approx(expect_e, abs=1e-6)
        np.testing.assert_allclose(moved[i, [0, 2]], still[i, [0, 2]], atol=1e-9)


def test_physics_carries_the_bubbles_with_a_varying_current():
    """A zero-mean Gauss-Markov current (sigma 0.1 m/s, tau 2 s): each live bubble's offset
    from the still-water run is the current summed over the physics steps since its release
    (an independent sum of the current the vehicle felt at each step)."""

    def scn(sigma: float) -> Scenario:
        return Scenario(name="plume", duration_s=20.0,
                        world={"seabed": {"depth_m": 30.0}, "movers": [HOVERING_DIVER],
                               "current": {"gauss_markov_sigma_mps": sigma, "gauss_markov_tau_s": 2.0}},
                        vehicle={"model": "bluerov2_heavy", "initial_pos_ned": (0.0, 0.0, 5.0)})

    out = []
    for sigma in (0.0, 0.1):
        phys = Physics(scn(sigma))
        phys.reset((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
        cmd = np.zeros(phys.params.n_thrusters)
        t, v = [], []
        for _ in range(int(round(9.0 / phys.dt_s))):
            t.append(phys.t_s)
            v.append(phys.current.velocity_ned)
            phys.step(cmd)
        ids = phys.movers._bubble_slots["diver"]
        out.append((np.array(t), np.array(v), phys.movers.plumes["diver"], phys.data.mocap_pos[ids].copy(), phys.dt_s))
    (_, _, plume, still, dt), (t, v, _, moved, _) = out
    assert np.abs(v).max() > 0.05
    m, t_last = plume.cfg.per_breath, t[-1]
    checked = 0
    for k in np.nonzero((plume.release_t_s <= t_last) & (plume.release_t_s > t_last - plume.cfg.lifetime_s))[0]:
        tk = plume.release_t_s[k]
        i0 = np.searchsorted(t, tk, side="right") - 1  # the step that holds the release
        disp = v[i0] * (t[i0] + dt - tk) + (v[i0 + 1:-1] * dt).sum(axis=0)
        sl = slice((k % plume.n_slots) * m, (k % plume.n_slots + 1) * m)
        np.testing.assert_allclose(moved[sl] - still[sl], np.broadcast_to(disp, (m, 3)), atol=1e-9)
        checked += 1
    assert checked >= 2


def test_rendered_breaths_apart_from_the_diver_are_refused_by_the_gating(monkeypatch):
    """The ARIS 3000 (1.8 MHz) renders a diver lying across the beam 8 m ahead and two
    breaths wholly apart from it: one 1 m beyond it in range (inside the fused filter's ROI)
    and one 2 m to starboard of its feet (outside). The paper's contour detector sees each as
    a cluster of its own; the ROI refuses the second, the size gate the first, and the
    diver's cluster is kept and chosen."""
    from autonomy.tracking.config import TrackingConfig
    from autonomy.tracking.onboard import TrackingStack, cut_by_edge, roi_score, shape_gate
    from autonomy.tracking.roi import polar_roi
    from scenarios.load import load_scenario
    from sim.sensors.registry import build_sensors

    scn = load_scenario("scenarios/track_static_vehicle.yaml", ["duration_s=5"])
    phys = Physics(scn)
    phys.reset((0.0, 0.0, 5.0), (0.0, 0.0, 0.0))
    fls = build_sensors({"fls": scn.sensors.fls}, phys.site_pos_body, 0)["fls"]
    mv = phys.movers
    monkeypatch.setattr(mv, "apply", lambda data, t: None)  # hold the poses set here
    diver = np.array([8.0, -1.3, 5.0])
    mid = mv._slots[0][0]
    phys.data.mocap_pos[mid] = diver
    phys.data.mocap_quat[mid] = (math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4))  # course east
    rng = np.random.default_rng(1)
    beyond, starboard = np.array([9.0, -1.3, 4.6]), np.array([8.0, 1.5, 4.6])
    ids = mv._bubble_slots["diver"]
    pos = np.tile([0.0, 0.0, -1000.0], (len(ids), 1))
    pos[:5] = beyond + 0.08 * rng.standard_normal((5, 3)) * [1.0, 1.0, 0.3]
    pos[5:10] = starboard + 0.08 * rng.standard_normal((5, 3)) * [1.0, 1.0, 0.3]
    phys.data.mocap_pos[ids] = pos
    truth = phys.truth()
    frame = fls.measure(truth, phys.scene(), noise=True).frame

    cfg = TrackingConfig(sonar_range_sigma_m=0.25, sonar_azimuth_sigma_deg=1.5)
    stack = TrackingStack(cfg, scn.autonomy.atr.classical, sonar_mount_body_m=fls.mount.pos_body_m)
    g = frame.geometry
    boxes, scores, feats = stack.detector.clusters(frame.fan, g.m_per_px, geometry=g)
    cands = stack._centre_detections(frame, boxes, scores)
    head = truth.point_ned(fls.mount.pos_body_m)
    R_ns = truth.R_nb @ fls.R_bs

    def polar(p):
        rel = R_ns.T @ (p - head)
        return math.hypot(rel[0], rel[1]), math.atan2(rel[1], rel[0])

    def nearest(p):
        r, a = polar(p)
        d = [math.hypot(c.range_m * math.cos(c.azimuth_rad) - r * math.cos(a),
                        c.range_m * math.sin(c.azimuth_rad) - r * math.sin(a)) for c in cands]
        return int(np.argmin(d)), min(d)

    i_div, d_div = nearest(diver)
    i_bey, d_bey = nearest(beyond)
    i_stb, d_stb = nearest(starboard)
    assert len({i_div, i_bey, i_stb}) == 3 and max(d_div, d_bey, d_stb) < 0.5  # three clusters, each where it is
    # the fused filter's ROI about the diver (0.25 m sigma, 2.45 sigma + the 1 m target size)
    roi = polar_roi(diver, np.diag([0.25**2, 0.25**2, 0.1**2]), head, R_ns, cfg.roi_sigma, cfg.target_size_m)
    gate = shape_gate(feats, cfg.target_size_m, cfg.min_extent_frac, cfg.min_area_frac,
                      cut_by_edge(feats, stack.detector.cfg.blur_sigma_m + g.m_per_px))
    inside, s = roi_score(cands, roi, gate)
    assert inside[i_div] and inside[i_bey] and not inside[i_stb]
    assert gate[i_div] and not gate[i_bey]
    assert int(np.argmax(s)) == i_div and s[i_div] >= cfg.detector_score_threshold
