"""Baseline returns on the auvsim gym environments: a scripted lawnmower, the inspection
planner and a random policy.

The lawnmower policy flies the scenario's own lawnmower plan through the env's action
interface: the onboard LOS guidance (``autonomy.guidance.survey``) turns the navigation
estimate into a speed/heading/altitude setpoint, which is mapped back to the normalised
action (yaw rate towards the LOS heading). The inspection policy (with ``--sonar``) is the
onboard active-inspection guidance (``autonomy.guidance.inspection``, the shipped defaults):
a coarse coverage pass, then legs towards the world model's confirmed, uncertain objects; it
reads the episode's onboard world model (what the observation's ``anchors`` table summarises)
and flies through the same action mapping. On ``Waypoint-v1`` the scripted policy steers
straight at the current waypoint (setpoint action mode).

    python scripts/gym_baselines.py [--scenario cssn_lawnmower] [--episodes 2] [--sonar]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from autonomy.frames import wrap_angle
from autonomy.guidance.config import InspectionConfig
from autonomy.guidance.inspection import InspectionGuidance
from autonomy.guidance.survey import SurveyGuidance
from sim.envs.survey_env import SurveyEnv, SurveyEnvOptions
from sim.envs.waypoint_env import WaypointEnv, WaypointEnvOptions


def _to_unit(value: float, lo: float, hi: float) -> float:
    return float(np.clip(2.0 * (value - lo) / (hi - lo) - 1.0, -1.0, 1.0))


class LawnmowerPolicy:
    """Follows the scenario's lawnmower with LOS guidance through SurveyEnv actions."""

    def __init__(self, env: SurveyEnv) -> None:
        scn = env.scenario
        self.env = env
        self.guidance = SurveyGuidance.from_config(scn.autonomy.guidance.survey, scn.autonomy.guidance.los,
                                                   swath_width_m=None if env.mission.fls is None
                                                   else env.mission.fls.swath_width_m(
                                                       scn.autonomy.guidance.survey.altitude_m))

    def reset(self) -> None:
        nav = self.env.nav
        self.guidance.start(nav.pos_ned[:2], float(nav.rpy_rad[2]))

    def __call__(self) -> np.ndarray:
        env, opts = self.env, self.env.options
        sp = self.guidance.update(env.nav)
        err = float(wrap_angle(sp.heading_rad - env.heading_setpoint_rad))
        rate = np.clip(err / (env.max_yaw_rate_radps * env.decision_interval_s), -1.0, 1.0)
        alt = sp.altitude_m if sp.altitude_m is not None else float(np.mean(opts.altitude_range_m))
        return np.array([_to_unit(sp.speed_mps, *opts.speed_range_mps), rate,
                         _to_unit(alt, *opts.altitude_range_m)], dtype=np.float32)


class InspectionPolicy(LawnmowerPolicy):
    """The onboard inspection guidance through SurveyEnv actions (needs the env's sonar and
    perception: ``SurveyEnvOptions(sonar=True)``)."""

    def __init__(self, env: SurveyEnv, cfg: InspectionConfig = InspectionConfig(enabled=True)) -> None:
        scn = env.scenario
        self.env = env
        fls = env.mission.fls
        if fls is None or not env.options.sonar:
            raise ValueError("InspectionPolicy needs the Survey env's sonar and world model (--sonar)")
        survey, loc = scn.autonomy.guidance.survey, scn.autonomy.localization
        self.guidance = InspectionGuidance.from_config(
            survey, cfg, scn.autonomy.guidance.los, swath_width_m=fls.swath_width_m(survey.altitude_m),
            fov_rad=fls.geometry.fov_rad, range_sigma_m=loc.range_sigma_m,
            azimuth_sigma_rad=loc.azimuth_sigma_rad + loc.attitude_sigma_rad, altitude_sigma_m=loc.altitude_sigma_m,
            tilt_rad=fls.tilt_down_rad, vertical_beam_rad=fls.geometry.vertical_beamwidth_rad)
        self._scans = -1

    def reset(self) -> None:
        super().reset()
        self._scans = -1

    def __call__(self) -> np.ndarray:
        perception = self.env.mission.perception
        if perception.pmha.n_scans != self._scans:  # a world-model update since the last decision
            self._scans = perception.pmha.n_scans
            self.guidance.on_world_model(self.env.mission.t_s, perception.world_objects())
        return super().__call__()


def waypoint_pursuit(env: WaypointEnv) -> np.ndarray:
    wp = env.waypoint_ned()
    pos = env.task.pos_ned
    bearing = math.atan2(wp[1] - pos[1], wp[0] - pos[0])
    err = float(wrap_angle(bearing - env.task.heading_setpoint_rad))
    d_lo, d_hi = env.options.depth_range_m
    return np.array([0.2, np.clip(err / (env.max_yaw_rate_radps * env.decision_interval_s), -1, 1),
                     _to_unit(wp[2], d_lo, d_hi)], dtype=np.float32)


def _episode(env, policy, seed: int, reset_hook=None) -> tuple[float, int, dict]:
    env.reset(seed=seed)
    if reset_hook is not None:
        reset_hook()
    ret, n = 0.0, 0
    while True:
        _, r, term, trunc, info = env.step(policy())
        ret += r
        n += 1
        if term or trunc:
            return ret, n, info


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="cssn_lawnmower")
    ap.add_argument("--episodes", type=int, default=2)
    ap.add_argument("--sonar", action="store_true", help="Survey-v1 with FLS + ATR + PMHA (slow)")
    ap.add_argument("--survey-time-s", type=float, default=600.0, help="Survey-v1 time limit")
    ap.add_argument("--set", dest="overrides", action="append", default=[], help="scenario key=value")
    args = ap.parse_args()
    over = tuple(args.overrides)

    survey = SurveyEnv(args.scenario, SurveyEnvOptions(sonar=args.sonar, max_episode_s=args.survey_time_s),
                       overrides=over)
    lawnmower = LawnmowerPolicy(survey)
    rng = np.random.default_rng(0)
    print(f"Survey-v1 ({args.scenario}, sonar={'on' if args.sonar else 'off'})")
    policies = [("lawnmower", lawnmower, lawnmower.reset)]
    if args.sonar:
        survey.reset(seed=0)
        inspection = InspectionPolicy(survey)
        policies.append(("inspection", inspection, inspection.reset))
    policies.append(("random", lambda: rng.uniform(-1, 1, 3).astype(np.float32), None))
    for name, policy, hook in policies:
        for ep in range(args.episodes):
            ret, n, info = _episode(survey, policy, ep, hook)
            line = (f"  {name:10s} episode {ep}: return {ret:8.2f}  steps {n:4d}  coverage "
                    f"{info['coverage_fraction']:.2f}  targets {info['targets_found']}/{len(survey.targets_ned)}  "
                    f"collision {info['collision']}  left area {info['left_area']}")
            if args.sonar:
                wm = survey.mission.perception.world_model_metrics()
                err = wm["mean_position_error_m"]
                line += (f"  map {wm['matched']} matched {wm['false']} false, mean error "
                         f"{'n/a' if err is None or err != err else f'{err:.2f} m'}")
            print(line, flush=True)

    wp = WaypointEnv(args.scenario, WaypointEnvOptions(action_mode="setpoint"), overrides=over)
    print(f"Waypoint-v1 ({args.scenario}, setpoint actions)")
    for name, policy in (("pursuit", lambda: waypoint_pursuit(wp)),
                         ("random", lambda: rng.uniform(-1, 1, 3).astype(np.float32))):
        for ep in range(args.episodes):
            ret, n, info = _episode(wp, policy, ep)
            print(f"  {name:9s} episode {ep}: return {ret:8.2f}  steps {n:4d}  waypoints "
                  f"{info['waypoints_reached']}/{wp.options.n_waypoints}  collision {info['collision']}  "
                  f"left area {info['left_area']}")


if __name__ == "__main__":
    main()
