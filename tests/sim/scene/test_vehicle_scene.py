"""Hull spec, attach into a world, MJCF asset, parameter files, determinism."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest

from scenarios.config.vehicle import ThrusterOverrides, VehicleConfig
from scenarios.config.world import CurrentConfig
from sim.dynamics.current import OceanCurrent
from sim.dynamics.hull import build_hull_spec, build_standalone_spec
from sim.rng import component_rng
from sim.dynamics.vehicle import VehicleDynamics
from scenarios.vehicle_params import (
    SENSOR_NAMES,
    VehicleParamsError,
    load_params_file,
    load_vehicle_params,
    params_path,
)

MODELS = ("feelhippo", "remus100", "bluerov2_heavy")


def _world_with_hull(params, dt_s=0.005):
    model = build_standalone_spec(params, timestep_s=dt_s, seabed_depth_m=4.0).compile()
    return model, mujoco.MjData(model)


@pytest.mark.parametrize("model_name", MODELS)
def test_hull_attaches_compiles_and_steps_without_warnings(model_name):
    p = load_vehicle_params(VehicleConfig(model=model_name))
    model, data = _world_with_hull(p)
    bid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "hull/vehicle")
    assert bid > 0
    assert model.body_mass[bid] == pytest.approx(p.mass_kg)
    np.testing.assert_allclose(model.body_ipos[bid], p.r_bg_m, atol=1e-12)
    np.testing.assert_allclose(np.sort(model.body_inertia[bid]), np.sort(np.linalg.eigvalsh(p.inertia_cg_kgm2)))
    for name in SENSOR_NAMES:
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"hull/{name}")
        np.testing.assert_allclose(model.site_pos[sid], p.sensors[name].pos_body_m, atol=1e-12)
    for j, name in enumerate(p.thruster_names):
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"hull/thruster_{name}")
        np.testing.assert_allclose(model.site_pos[sid], p.layout.pos_body_m[j], atol=1e-12)
        # Site x axis along the thrust direction.
        R = np.zeros(9)
        mujoco.mju_quat2Mat(R, model.site_quat[sid])
        np.testing.assert_allclose(R.reshape(3, 3)[:, 0], p.layout.dir_body[j], atol=1e-9)
    dyn = VehicleDynamics(model, data, p)
    assert dyn.body_id == bid
    dyn.reset([0.0, 0.0, 2.0], [0.05, -0.05, 0.3])
    cmd = np.full(p.n_thrusters, 0.5)
    for _ in range(200):  # 1 s
        dyn.step_inputs(cmd, model.opt.timestep)
        mujoco.mj_step(model, data)
    assert all(w.number == 0 for w in data.warning)
    assert np.all(np.isfinite(data.qpos)) and np.linalg.norm(dyn.nu()[:3]) > 0.05


def test_hull_collides_with_seabed():
    """Hull collision geom rests on the seabed instead of sinking through it."""
    p = load_vehicle_params(VehicleConfig(buoyancy_fraction=0.9))
    model, data = _world_with_hull(p)
    dyn = VehicleDynamics(model, data, p)
    dyn.reset([0.0, 0.0, 3.0], [0.0, 0.0, 0.0])
    for _ in range(2000):
        dyn.step_inputs([0.0] * 4, model.opt.timestep)
        mujoco.mj_step(model, data)
    z = dyn.truth(10.0).pos_ned[2]
    assert 4.0 - 0.5 * p.hull.size_m[2] - 0.02 < z < 4.0 - 0.5 * p.hull.size_m[2] + 0.02


def test_committed_mjcf_matches_params():
    """sim/assets/feelhippo/feelhippo.xml (scripts/make_feelhippo_mesh.py) is in sync."""
    p = load_vehicle_params(VehicleConfig(model="feelhippo"))
    xml = Path(params_path("feelhippo")).parent / "feelhippo.xml"
    m_xml = mujoco.MjModel.from_xml_path(str(xml))
    m_spec = build_hull_spec(p).compile()
    assert m_xml.nsite == m_spec.nsite and m_xml.ngeom == m_spec.ngeom
    np.testing.assert_allclose(m_xml.body_mass, m_spec.body_mass)
    np.testing.assert_allclose(m_xml.body_inertia, m_spec.body_inertia)
    np.testing.assert_allclose(m_xml.body_ipos, m_spec.body_ipos)
    np.testing.assert_allclose(m_xml.site_pos, m_spec.site_pos, atol=1e-6)
    np.testing.assert_allclose(m_xml.mesh_vert, m_spec.mesh_vert, atol=1e-6)
    import trimesh

    mesh = trimesh.load_mesh(p.hull.visual_mesh_path)  # body frame, before MuJoCo recentres it
    assert np.all(mesh.bounds[1] - mesh.bounds[0] <= p.envelope_m + 1e-6)
    assert len(mesh.faces) < 5000


def test_same_seed_same_trajectory_bit_for_bit():
    p = load_vehicle_params(VehicleConfig())
    cfg = CurrentConfig(velocity_ned_mps=(0.1, 0.0, 0.0), gauss_markov_sigma_mps=0.1,
                        gauss_markov_tau_s=5.0)

    def trajectory(seed):
        model, data = _world_with_hull(p)
        dyn = VehicleDynamics(model, data, p, cfg, component_rng(seed, "current"))
        dyn.reset([0.0, 0.0, 2.0], [0.0, 0.0, 0.0])
        out = []
        for k in range(400):
            dyn.step_inputs([0.6, 0.4, 0.2, 0.1], model.opt.timestep)
            mujoco.mj_step(model, data)
            out.append(data.qpos.copy())
        return np.array(out)

    a, b, c = trajectory(3), trajectory(3), trajectory(4)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_gauss_markov_current_statistics():
    """Stationary std sigma and lag-k autocorrelation exp(-k dt / tau)."""
    cfg = CurrentConfig(velocity_ned_mps=(0.2, -0.1, 0.0), gauss_markov_sigma_mps=0.05,
                        gauss_markov_tau_s=2.0)
    cur = OceanCurrent(cfg, np.random.default_rng(0))
    dt = 0.1
    x = np.array([cur.step(dt) for _ in range(100_000)])
    assert np.all(x[:, 2] == 0.0)
    dev = x[2000:, :2] - [0.2, -0.1]
    np.testing.assert_allclose(dev.std(axis=0), 0.05, rtol=0.05)
    rho = np.mean(dev[:-10, 0] * dev[10:, 0]) / dev[:, 0].var()
    assert rho == pytest.approx(np.exp(-10 * dt / 2.0), abs=0.03)
    with pytest.raises(ValueError, match="rng"):
        OceanCurrent(cfg, None)


def test_scenario_overrides():
    base = load_vehicle_params(VehicleConfig())
    p = load_vehicle_params(VehicleConfig(mass_kg=40.0, buoyancy_fraction=1.02,
                                          thrusters=ThrusterOverrides(time_constant_s=0.3,
                                                                      dead_zone=0.1,
                                                                      thrust_scale=0.5)))
    assert p.mass_kg == 40.0 and p.buoyancy_n == pytest.approx(1.02 * 40.0 * 9.81)
    np.testing.assert_allclose(p.inertia_cg_kgm2, base.inertia_cg_kgm2 * 40.0 / 35.0)
    np.testing.assert_allclose(p.thruster_time_constant_s, 0.3)
    np.testing.assert_allclose(p.layout.dead_zone, 0.1)
    np.testing.assert_allclose(p.layout.max_fwd_n, 0.5 * base.layout.max_fwd_n)
    frac = load_vehicle_params(VehicleConfig(mass_kg=40.0))
    assert frac.buoyancy_n / frac.weight_n == pytest.approx(base.buoyancy_n / base.weight_n)


def test_bad_parameter_files_name_file_and_key(tmp_path):
    good = params_path("feelhippo").read_text()
    bad = tmp_path / "params.yaml"
    bad.write_text(good.replace("mass_kg: 35.0", "mass_kg: 35.0\nmass_kgs: 3"))
    with pytest.raises(VehicleParamsError, match=r"params\.yaml.*\n.*mass_kgs"):
        load_params_file(bad)
    bad.write_text(good.replace("mass_kg: 35.0", "mass_kg: -1"))
    with pytest.raises(VehicleParamsError, match="mass_kg"):
        load_params_file(bad)
    bad.write_text(good.replace("added_mass: [16.3, 14.5, 22.7, 1.08, 1.02, 0.99]", "added_mass: [1, 2]"))
    with pytest.raises(VehicleParamsError, match="added_mass"):
        load_params_file(bad)
    bad.write_text(good.replace("  gps:", "  gpsx:"))
    with pytest.raises(VehicleParamsError, match="gps"):
        load_params_file(bad)
    with pytest.raises(VehicleParamsError, match="not found"):
        load_params_file(tmp_path / "nope.yaml")


def test_current_is_advanced_once_per_step_by_its_owner():
    """A CurrentConfig is built and advanced by the dynamics; an OceanCurrent passed in is
    the caller's to advance (the dynamics only reads it)."""
    p = load_vehicle_params(VehicleConfig())
    cfg = CurrentConfig(gauss_markov_sigma_mps=0.2, gauss_markov_tau_s=1.0)
    model, data = _world_with_hull(p)
    dyn = VehicleDynamics(model, data, p, cfg, component_rng(1, "current"))
    ref = OceanCurrent(cfg, component_rng(1, "current"))
    for _ in range(5):
        dyn.step_inputs([0.0] * 4, 0.005)
        ref.step(0.005)
    assert dyn.current.velocity_tuple == ref.velocity_tuple
    external = OceanCurrent(cfg, component_rng(1, "current"))
    dyn2 = VehicleDynamics(model, data, p, external)
    dyn2.step_inputs([0.0] * 4, 0.005)
    assert external.velocity_tuple == (0.0, 0.0, 0.0)
