"""A scene with the AUV and a surface buoy: stepping, truth, sonar blindness to the buoy,
contact detection, independence of the AUV, placement checks."""

from __future__ import annotations

import numpy as np
import pytest

from scenarios.load import ScenarioError, load_scenario
from sim.scene.physics import Physics
from sim.sensors.raycast import NO_HIT_ID

BUOY_AT = "vehicles.buoy.initial_pos_ne_m=[3,0]"


def _physics(*overrides: str) -> tuple[Physics, object]:
    scn = load_scenario("cssn_lawnmower", ["physics.rate_hz=100", *overrides])
    phys = Physics(scn)
    phys.reset(scn.vehicle.initial_pos_ned, np.deg2rad(scn.vehicle.initial_rpy_deg))
    return phys, scn


def test_buoy_steps_on_the_same_clock_and_reports_its_truth():
    phys, scn = _physics(BUOY_AT, "vehicles.buoy.initial_heading_deg=30")
    assert set(phys.vehicles) == {"auv", "buoy"}
    t0 = phys.truth("buoy")
    np.testing.assert_allclose(t0.pos_ned, [3.0, 0.0, 0.0])
    assert t0.rpy_rad[2] == pytest.approx(np.deg2rad(30))
    phys.set_command("buoy", np.full(4, 0.6))  # all four forward: straight ahead
    phys.advance(np.zeros(phys.params.n_thrusters), 1000)
    t1 = phys.truth("buoy")
    assert t1.t_s == phys.truth().t_s == pytest.approx(10.0)
    assert t1.nu[0] > 0.2 and t1.pos_ned[2] == 0.0
    heading = np.array([np.cos(np.deg2rad(30)), np.sin(np.deg2rad(30))])
    moved = t1.pos_ned[:2] - t0.pos_ned[:2]
    assert moved @ heading > 2.0 and abs(heading[0] * moved[1] - heading[1] * moved[0]) < 0.05 * np.linalg.norm(moved)
    with pytest.raises(KeyError, match="no vehicle 'boat'"):
        phys.truth("boat")
    with pytest.raises(ValueError, match="needs 4 values"):
        phys.set_command("buoy", [0.1, 0.2])


def test_sonar_does_not_see_the_buoy_and_it_is_no_scene_object():
    phys, _ = _physics(BUOY_AT)
    single, _ = _physics()
    assert [o.name for o in phys.objects()] == [o.name for o in single.objects()]
    # Rays from the AUV's start towards the buoy's hull (4.3 m away, at its draft) and from
    # under it straight up: nothing within 10 m (the walls are 34 m away).
    caster = phys.scene().caster
    dirs = np.array([[-1.0, 0.0, 0.0], [-0.99, 0.1, 0.02], [-0.99, -0.1, 0.0]])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    hits = caster.cast(np.array([7.6, 0.0, 0.05]), dirs, 10.0)
    assert np.all(np.isinf(hits.dist_m)) and np.all(hits.object_id == NO_HIT_ID)
    up = caster.cast(np.array([3.0, 0.0, 2.0]), np.array([[0.0, 0.0, -1.0]]), 10.0)
    assert np.isinf(up.dist_m[0])
    down = caster.cast(np.array([3.0, 0.0, -1.0]), np.array([[0.0, 0.0, 1.0]]), 10.0)
    assert down.dist_m[0] == pytest.approx(5.0)  # straight through the buoy to the 4 m seabed


def test_contact_between_vehicles_is_detected():
    """Positive control for the no-contact checks: the buoy moved onto the surfaced AUV."""
    phys, _ = _physics(BUOY_AT)
    assert phys.vehicles_in_contact() == []
    import mujoco

    phys.extras["buoy"].reset((8.0, 0.0), 0.0)  # the AUV starts at (8, 0, 0.3)
    mujoco.mj_forward(phys.model, phys.data)
    assert phys.vehicles_in_contact() == [("auv", "buoy")]


def test_auv_trajectory_is_unchanged_by_a_distant_buoy():
    """Separate bodies: the AUV's state is bit-identical with or without the buoy."""
    phys, _ = _physics(BUOY_AT, "world.current.velocity_ned_mps=[0.1,0.1,0]")
    single, _ = _physics("world.current.velocity_ned_mps=[0.1,0.1,0]")
    cmd = np.array([0.6, 0.4, 0.1, -0.3])
    phys.set_command("buoy", np.array([0.5, -0.2, 0.3, 0.8]))
    for _ in range(5):
        phys.advance(cmd, 200)
        single.advance(cmd, 200)
        a, b = phys.truth(), single.truth()
        assert np.array_equal(a.pos_ned, b.pos_ned) and np.array_equal(a.nu, b.nu)


@pytest.mark.parametrize("override, message", [
    ("vehicles.buoy.initial_pos_ne_m=[8,0.5]", "overlaps the AUV at its start"),
    ("vehicles.buoy.initial_pos_ne_m=[25.9,0]", "into the basin walls"),
    ("vehicles.buoy.initial_pos_ne_m=[500,0]", "outside the seabed patch"),
    ("vehicles.auv.behaviour=follow", "vehicle name 'auv' is taken"),
    ("vehicles.buoy.behaviour=chase", "vehicles.buoy.behaviour"),
    ("vehicles.Buoy.behaviour=follow", "vehicles.Buoy"),
])
def test_bad_extra_vehicles_are_one_clear_error(override, message):
    with pytest.raises(ScenarioError, match=message):
        load_scenario("cssn_lawnmower", [override])


def test_buoy_over_a_shallow_target_is_rejected():
    with pytest.raises(ScenarioError, match=r"vehicles.buoy.initial_pos_ne_m: overlaps world.targets.0"):
        load_scenario("cssn_lawnmower", ["vehicles.buoy.initial_pos_ne_m=[0,10]", "world.seabed.depth_m=0.5",
                                         "world.targets.0.pos_ned=[0,10,0.5]",
                                         "autonomy.guidance.survey.vertical_mode=depth",
                                         "autonomy.guidance.survey.depth_m=0.1"])


def test_held_buoy_forces_match_per_step_forces():
    """At 200 Hz the buoy's forces are updated at 50 Hz and held: its track stays within
    1 % of the distance it made good (turning) of the same hull updated every step."""
    import mujoco

    from sim.dynamics.hull import VEHICLE_BODY, build_hull_spec
    from sim.dynamics.surface_vessel import SurfaceVesselDynamics

    phys, _ = _physics(BUOY_AT, "physics.rate_hz=200", "world.current.velocity_ned_mps=[0.1,-0.1,0]")
    assert phys._extra_every == 4
    cmd = np.array([0.9, 0.5, 0.8, 0.6])  # ahead, turning
    phys.set_command("buoy", cmd)
    phys.advance(np.zeros(phys.params.n_thrusters), 200 * 30)

    spec = mujoco.MjSpec()
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.timestep = phys.dt_s
    spec.worldbody.add_frame().attach_body(build_hull_spec(phys.extras["buoy"].params).body(VEHICLE_BODY), "b/", "")
    model = spec.compile()
    data = mujoco.MjData(model)
    ref = SurfaceVesselDynamics(model, data, phys.extras["buoy"].params, 1, phys.current)
    ref.reset((3.0, 0.0), 0.0)
    ref.set_command(cmd)
    for _ in range(200 * 30):
        ref.step_inputs(phys.dt_s)
        mujoco.mj_step(model, data)
    a, b = phys.truth("buoy"), ref.truth(30.0)
    travelled = float(np.hypot(*(b.pos_ned[:2] - [3.0, 0.0])))
    assert travelled > 3.0
    assert np.hypot(*(a.pos_ned[:2] - b.pos_ned[:2])) < 0.01 * travelled
