"""Forward-looking sonar detections are geolocalised with the pose of the frame's capture,
not the navigation estimate of its delivery (a latency and up to an autonomy period later)."""

from __future__ import annotations

import numpy as np

from autonomy.frames import rot_from_euler
from autonomy.messages import NavEstimate
from scenarios import load_scenario
from sim.mission import Mission
from sim.features.perception import Perception

# dived 10 m short of OPI1 heading for it (east): targets in view from the first frames
OVER = ["autonomy.guidance.mission.start_delay_s=0", "vehicle.initial_pos_ned=[0.0,0.0,2.0]", "duration_s=3.0",
        "autonomy.atr.detector=classical"]


def test_detections_are_placed_with_the_pose_of_the_capture_time():
    m = Mission(load_scenario("cssn_lawnmower", OVER))
    m.reset()
    late, at_capture = (Perception(m.scenario, m.fls, m.physics.world.seabed, m.parts.waypoints_ne)
                        for _ in range(2))
    n = 0
    for _ in range(4):
        for _ in range(67):
            m.physics.step(np.zeros(m.physics.params.n_thrusters))
        truth = m.physics.truth()
        render = m.fls.measure(truth, m.physics.scene())
        # the exact pose of the capture, moving east at 0.5 m/s; delivered 0.15 s later with
        # the estimate of then (the vehicle 7.5 cm further on)
        rpy, v_body = np.array([0.0, 0.0, 0.5 * np.pi]), np.array([0.5, 0.0, 0.0])
        pos = truth.pos_ned
        nav0 = NavEstimate(truth.t_s, pos, rpy, v_body, np.zeros(3), 0.01 * np.eye(3), altitude_m=2.0)
        nav1 = NavEstimate(truth.t_s + 0.15, pos + rot_from_euler(*rpy) @ v_body * 0.15, rpy, v_body, np.zeros(3),
                           0.01 * np.eye(3), altitude_m=2.0)
        a, b = late.process(render, nav1), at_capture.process(render, nav0)
        assert len(a.localized) == len(b.localized)
        for la, lb in zip(a.localized, b.localized):
            np.testing.assert_allclose(la.pos_ned, lb.pos_ned, rtol=0, atol=1e-9)
            n += 1
    assert n > 0
