"""Closed-loop checks: autopilots + thrust allocation + thrusters + Fossen model.

The vehicle is the FeelHippo preset integrated with the pure-numpy Fossen model
(``sim.dynamics.hydrodynamics.FossenModel``) and the thruster model (``sim.dynamics.thrusters``) in a
fixed-step loop (semi-implicit Euler, 50 Hz, attitude by the exact rotation of each step);
the autonomy runs at 10 Hz on perfect navigation. No MuJoCo.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.control.autopilot import Autopilot
from autonomy.control.config import ControlConfig, PidConfig
from autonomy.control.setpoint import Setpoint
from autonomy.frames import euler_from_rot, quat_from_rot, rot_from_euler, skew, wrap_angle
from autonomy.guidance.config import LosConfig
from autonomy.guidance.mission import MissionFsm, MissionState
from autonomy.guidance.survey import SurveyGuidance
from autonomy.messages import NavEstimate
from scenarios.load import load_scenario
from scenarios.schema import Scenario
from sim.dynamics.hydrodynamics import FossenModel
from sim.dynamics.thrusters import ThrusterArray
from scenarios.vehicle_params import load_vehicle_params

PHYSICS_DT_S = 0.02
CONTROL_EVERY = 5  # 10 Hz autonomy
SEABED_DEPTH_M = 4.0


def _rotation_step(omega_body: np.ndarray, dt_s: float) -> np.ndarray:
    """Exact rotation exp(S(omega) dt) (Rodrigues)."""
    angle = float(np.linalg.norm(omega_body)) * dt_s
    if angle < 1e-12:
        return np.eye(3)
    k = skew(omega_body / np.linalg.norm(omega_body))
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * k @ k


class Plant:
    """FeelHippo hull + thrusters in still water or a constant NED current."""

    def __init__(self, pos_ned, yaw_rad, current_ned=(0.0, 0.0, 0.0)):
        params = load_vehicle_params(Scenario(name="t").vehicle)
        self.model = FossenModel(params)
        self.thrusters = ThrusterArray(params)
        self.pos = np.array(pos_ned, dtype=float)
        self.R = rot_from_euler(0.0, 0.0, yaw_rad)
        self.nu = np.zeros(6)
        self.current = np.asarray(current_ned, dtype=float)
        self.t_s = 0.0

    def nav(self) -> NavEstimate:
        return NavEstimate(t_s=self.t_s, pos_ned=self.pos.copy(), rpy_rad=euler_from_rot(self.R),
                           vel_body_mps=self.nu[:3].copy(), rate_body_radps=self.nu[3:].copy(),
                           cov_pos_ned=np.zeros((3, 3)), altitude_m=SEABED_DEPTH_M - self.pos[2])

    def step(self, cmd: np.ndarray) -> None:
        tau = self.thrusters.step(cmd, PHYSICS_DT_S)
        self.model.mujoco_wrench(quat_from_rot(self.R), self.R @ self.nu[:3], self.nu[3:],
                                 self.current, tau)
        self.nu = self.nu + PHYSICS_DT_S * self.model.nu_dot()
        self.pos = self.pos + PHYSICS_DT_S * (self.R @ self.nu[:3])
        self.R = self.R @ _rotation_step(self.nu[3:], PHYSICS_DT_S)
        self.t_s += PHYSICS_DT_S


STOP = object()  # returned by a setpoint function to end the run


def fly(plant: Plant, duration_s: float, setpoint_fn, autopilot: Autopilot | None = None):
    """Run the loop; ``setpoint_fn(nav) -> Setpoint | None | STOP`` (None: idle, zero
    wrench; STOP ends the run). Returns a log."""
    ap = autopilot or Autopilot(ControlConfig())
    cmd = np.zeros(plant.thrusters.n)
    log = []
    for k in range(int(round(duration_s / PHYSICS_DT_S))):
        if k % CONTROL_EVERY == 0:
            nav = plant.nav()
            sp = setpoint_fn(nav)
            if sp is STOP:
                break
            wrench = np.zeros(6) if sp is None else ap.update(nav, sp, CONTROL_EVERY * PHYSICS_DT_S)
            cmd = plant.thrusters.allocate(wrench)
            log.append((plant.t_s, *plant.pos, *euler_from_rot(plant.R), *plant.nu[:3]))
        plant.step(cmd)
    return np.array(log)


def test_still_water_holds_depth_and_heading_through_steps():
    plant = Plant([0.0, 0.0, 0.3], math.radians(90.0))
    def sp(nav):  # dive to 2 m heading east, then turn to north at t = 60 s
        heading = math.radians(90.0) if nav.t_s < 60.0 else 0.0
        return Setpoint(0.5, heading, depth_m=2.0)
    log = fly(plant, 120.0, sp)
    t, depth, yaw, u = log[:, 0], log[:, 3], log[:, 6], log[:, 7]
    settled = (t > 40.0) & (t < 60.0) | (t > 100.0)
    assert np.max(np.abs(depth[settled] - 2.0)) < 0.1
    heading_ref = np.where(t < 60.0, math.radians(90.0), 0.0)
    assert np.max(np.abs(np.degrees(wrap_angle(yaw[settled] - heading_ref[settled])))) < 2.0
    assert np.max(np.abs(u[settled] - 0.5)) < 0.05
    # the 90 deg turn and the dive take a bounded time and do not overshoot badly
    assert np.max(depth) < 2.3
    assert np.all(np.abs(depth[t > 25.0] - 2.0) < 0.15)


def test_altitude_mode_holds_altitude_over_flat_seabed():
    plant = Plant([0.0, 0.0, 0.3], 0.0)
    log = fly(plant, 60.0, lambda nav: Setpoint(0.5, 0.0, altitude_m=1.5))
    t, depth = log[:, 0], log[:, 3]
    altitude = SEABED_DEPTH_M - depth[t > 30.0]
    assert np.max(np.abs(altitude - 1.5)) < 0.1


def _line_in_cross_current(compensate: bool, sway_control: bool):
    """Eastbound 45 m line at 2 m depth with a 0.2 m/s northward current across it."""
    plant = Plant([0.0, 0.0, 2.0], math.radians(90.0), current_ned=(0.2, 0.0, 0.0))
    los = LosConfig(lookahead_m=3.0, sideslip_compensation=compensate)
    guidance = SurveyGuidance([[0.0, 45.0]], 0.5, los, depth_m=2.0)
    guidance.start([0.0, 0.0], math.radians(90.0))
    cfg = ControlConfig() if sway_control else ControlConfig(sway=PidConfig())
    log = fly(plant, 130.0, lambda nav: STOP if guidance.finished else guidance.update(nav),
              Autopilot(cfg))
    assert guidance.finished, "did not reach the end of the line"
    t, north, east, depth = log[:, 0], log[:, 1], log[:, 2], log[:, 3]
    cross_track = -north  # starboard of an eastbound line is south
    assert np.max(np.abs(depth[t > 10.0] - 2.0)) < 0.1
    steady = t > 40.0
    # progress along the line at the commanded speed despite the current
    assert np.mean(np.diff(east[steady]) / np.diff(t[steady])) > 0.45
    return t, cross_track, log[:, 7], log[:, 8]


@pytest.mark.parametrize("sway_control", [True, False])
def test_cross_current_rejected_with_course_control(sway_control):
    t, e, _, _ = _line_in_cross_current(compensate=True, sway_control=sway_control)
    assert np.max(np.abs(e)) < 1.0
    assert np.max(np.abs(e[t > 40.0])) < 0.1


def test_plain_los_in_cross_current_settles_at_the_analytic_offset():
    """Without sideslip compensation or sway thrust the vehicle crabs: its ground course is
    heading + beta (beta = atan2(v, u)), and plain LOS settles where the commanded heading
    path - atan(e / Delta) equals path - beta: e = Delta tan(beta)."""
    t, e, u, v = _line_in_cross_current(compensate=False, sway_control=False)
    steady = t > 40.0
    beta = np.arctan2(v[steady], u[steady])
    np.testing.assert_allclose(e[steady], 3.0 * np.tan(beta), rtol=0.03)
    # pushed to port (north) by the current: bounded, but clearly worse than course control
    assert -1.5 < np.mean(e[steady]) < -0.8


def test_cssn_lawnmower_mission_visits_every_waypoint():
    scenario = load_scenario("cssn_lawnmower")
    g = scenario.autonomy.guidance
    guidance = SurveyGuidance.from_config(g.survey, g.los)
    fsm = MissionFsm(g.mission, guidance)
    x0 = scenario.vehicle.initial_pos_ned
    plant = Plant(x0, math.radians(scenario.vehicle.initial_rpy_deg[2]))
    ap = Autopilot(scenario.autonomy.control)
    log = fly(plant, 720.0, lambda nav: STOP if fsm.done else fsm.update(nav.t_s, nav, True), ap)
    assert fsm.succeeded, fsm.transitions
    assert [tr.to_state for tr in fsm.transitions] == [
        MissionState.DIVE, MissionState.SURVEY, MissionState.SURFACE, MissionState.DONE]
    wm = guidance.manager
    assert np.all(np.isfinite(wm.reached_t_s)), "some waypoints never reached"
    miss_m = np.linalg.norm(wm.reached_pos_ne_m - wm.waypoints_ne_m, axis=1)
    assert np.max(miss_m) < g.los.acceptance_radius_m + 0.5
    t = log[:, 0]
    assert t[-1] < 12 * 60.0
    # while surveying the legs: altitude held and the path stays on the legs
    survey_t0 = fsm.transitions[1].t_s
    survey_t1 = fsm.transitions[2].t_s
    on = (t > survey_t0 + 5.0) & (t < survey_t1)
    assert np.max(np.abs((SEABED_DEPTH_M - log[on, 3]) - g.survey.altitude_m)) < 0.15
