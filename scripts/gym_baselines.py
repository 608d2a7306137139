"""Baseline returns on the auvsim gym environments: a scripted lawnmower and a random policy.

The lawnmower policy flies the scenario's own lawnmower plan through the env's action
interface: the onboard LOS guidance (``autonomy.guidance.survey``) turns the navigation
estimate into a speed/heading/altitude setpoint, which is mapped back to the normalised
action (yaw rate towards the LOS heading). On ``Waypoint-v1`` the scripted policy steers
straight at the current waypoint (setpoint action mode).

    python scripts/gym_baselines.py [--scenario cssn_lawnmower] [--episodes 2] [--sonar]
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from autonomy.frames import wrap_angle
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
    for name, policy, hook in (("lawnmower", lawnmower, lawnmower.reset),
                               ("random", lambda: rng.uniform(-1, 1, 3).astype(np.float32), None)):
        for ep in range(args.episodes):
            ret, n, info = _episode(survey, policy, ep, hook)
            print(f"  {name:9s} episode {ep}: return {ret:8.2f}  steps {n:4d}  coverage "
                  f"{info['coverage_fraction']:.2f}  targets {info['targets_found']}/{len(survey.targets_ned)}  "
                  f"collision {info['collision']}  left area {info['left_area']}")

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
