"""The buoy's autonomy in closed loop with the simulated physics and sensors: GNSS station
keeping in a current, following a moving point, and a two-vehicle mission."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from scenarios.load import load_scenario
from sim.features import SeaTrialFeature
from sim.mission import Mission
from sim.scene.physics import Physics
from sim.events.scheduler import SensorScheduler
from sim.features.surface_runner import SurfaceVehicleRunner

STATION = np.array([3.0, 8.0])


class _Ticked:
    """A runner's declared events on a scheduler of their own, ticked every ``period_s``."""

    def __init__(self, runner: SurfaceVehicleRunner, period_s: float) -> None:
        self.runner, self.clock, self.events = runner, SensorScheduler(eps_s=1e-9), {}
        for name, rate_hz, event in runner.periodic_events():
            self.clock.add(name, rate_hz, quantum_s=period_s)
            self.events[name] = event

    def tick(self, target=None) -> None:
        auv = None if target is None else SimpleNamespace(pos_ned=np.asarray(target, dtype=float))
        for _, name in self.clock.take_due(self.runner.physics.t_s):
            self.events[name](auv)

    @property
    def n_gnss_fixes(self) -> int:
        return self.runner.n_gnss_fixes


def _buoy_scene(*overrides: str) -> tuple[Physics, _Ticked]:
    # 50 Hz physics: the buoy's fastest mode (rotor lag 0.2 s) is well resolved.
    scn = load_scenario("cssn_lawnmower", ["physics.rate_hz=50", "vehicles.buoy.initial_pos_ne_m=[0,5]", *overrides])
    phys = Physics(scn)
    phys.reset(scn.vehicle.initial_pos_ned, np.zeros(3))
    runner = _Ticked(SurfaceVehicleRunner(phys, "buoy", scn.vehicles["buoy"], seed=11), 5 * phys.dt_s)
    runner.tick()  # t = 0: the first firings
    return phys, runner


@pytest.mark.parametrize("current", ["[0,0.2,0]", "[-0.1414,-0.1414,0]"])
def test_gnss_station_keeping_holds_within_1m_in_a_0p2_current(current):
    """GNSS noise 0.7 m per axis (1 m horizontal rms) at 1 Hz; after 150 s of settling the
    true position stays within 1 m of the station 95 % of the time."""
    phys, runner = _buoy_scene(f"world.current.velocity_ned_mps={current}",
                               "vehicles.buoy.station_ne_m=[3,8]")
    dist = []
    while phys.t_s < 400.0:
        phys.advance(np.zeros(phys.params.n_thrusters), 5)
        runner.tick()
        if phys.t_s > 150.0:
            dist.append(math.hypot(*(phys.truth("buoy").pos_ned[:2] - STATION)))
    dist = np.array(dist)
    assert runner.n_gnss_fixes == pytest.approx(400, abs=2)
    assert np.percentile(dist, 95) < 1.0, f"p95 {np.percentile(dist, 95):.2f} m, mean {dist.mean():.2f} m"
    # The bow weathervanes into the current (its drag is then the smallest).
    cur = np.array([float(x) for x in current.strip("[]").split(",")[:2]])
    heading = phys.truth("buoy").rpy_rad[2]
    assert abs(math.remainder(heading - math.atan2(-cur[1], -cur[0]), 2 * math.pi)) < 0.6


def test_follows_a_point_moving_at_0p5_mps_5m_behind():
    """The followed point runs 40 m east at 0.5 m/s (paper 000's survey speed), turns north
    and comes back west; the buoy (top speed ~0.65 m/s) holds 5 m behind it on its course."""
    phys, runner = _buoy_scene("vehicles.buoy.behaviour=follow", "vehicles.buoy.offset_m=[-5,0]",
                               "vehicles.buoy.initial_pos_ne_m=[0,-8]", "vehicles.buoy.initial_heading_deg=90",
                               "world.current.velocity_ned_mps=[0.1,0,0]")

    def target(t: float) -> np.ndarray:
        if t < 80.0:
            return np.array([0.0, -3.0 + 0.5 * t, 2.0])
        if t < 100.0:
            return np.array([0.25 * (t - 80.0), 37.0, 2.0])
        return np.array([5.0, 37.0 - 0.5 * (t - 100.0), 2.0])

    err = []
    while phys.t_s < 200.0:
        phys.advance(np.zeros(phys.params.n_thrusters), 5)
        runner.tick(target(phys.t_s))
        goal = target(phys.t_s)[:2] + (np.array([0.0, -5.0]) if phys.t_s < 80.0 else np.array([0.0, 5.0]))
        err.append((phys.t_s, math.hypot(*(phys.truth("buoy").pos_ned[:2] - goal))))
    err = np.array(err)
    out_leg = err[(err[:, 0] > 40.0) & (err[:, 0] < 80.0), 1]
    back_leg = err[err[:, 0] > 170.0, 1]
    assert out_leg.max() < 1.0, f"first leg: max {out_leg.max():.2f} m"
    assert back_leg.max() < 1.5, f"after the turn: max {back_leg.max():.2f} m"


def test_two_vehicle_mission_no_contact_and_auv_unchanged():
    """The buoy follows the surveying AUV 5 m behind; the hulls never touch, the AUV's run is
    the single-vehicle one exactly (the buoy's sensors draw from their own generators)."""
    common = ["duration_s=40", "sensors.fls=null"]
    two = Mission(load_scenario("cssn_lawnmower", common + ["vehicles.buoy.initial_pos_ne_m=[3,0]",
                                                            "vehicles.buoy.behaviour=follow"]), perception=False)
    one = Mission(load_scenario("cssn_lawnmower", common), perception=False)
    two.reset()
    one.reset()
    sep = []
    while not one.done:
        a, b = two.step(), one.step()
        assert np.array_equal(a.truth.pos_ned, b.truth.pos_ned)
        assert two.physics.vehicles_in_contact() == []
        sep.append(math.hypot(*(two.physics.truth("buoy").pos_ned[:2] - a.truth.pos_ned[:2])))
    assert two.done and min(sep) > 1.5
    assert two.feature(SeaTrialFeature).surface_vehicles["buoy"].n_gnss_fixes >= 39
