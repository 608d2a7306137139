"""Seabed from a bathymetry file: GeoTIFF/XYZ/npy round trips to the mesh, the DVL and the
altimeter over it, and the load-time errors. Expected depths come from the analytic
surface the files were written from, never from the code's own grid."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

rasterio = pytest.importorskip("rasterio")
from rasterio.transform import from_origin  # noqa: E402

from scenarios import load_scenario  # noqa: E402
from scenarios.bathymetry import BathymetryError, read_depth_grid  # noqa: E402
from scenarios.config.world import BathymetryFileConfig, SeabedConfig  # noqa: E402
from scenarios.load import ScenarioError, scenarios_dir  # noqa: E402
from sim.scene.seabed import make_seabed  # noqa: E402

E0, N0 = 600000.0, 5100000.0  # projected coordinates of the south-west node
SPACING = 2.0
NX, NY = 41, 36  # nodes north, east


def surface_depth_m(n_m, e_m):
    """Smooth analytic bed (positive down): a plane with a gentle bowl, curvature 0.004 /m."""
    n_m, e_m = np.asarray(n_m, float), np.asarray(e_m, float)
    return 12.0 + 0.05 * n_m - 0.03 * e_m + 0.002 * (n_m - 40.0) ** 2 + 0.001 * (e_m - 30.0) ** 2


def write_tif(path: Path, *, crs="EPSG:32633", values=None, nodata=-9999.0) -> None:
    n = np.arange(NX) * SPACING
    e = np.arange(NY) * SPACING
    nn, ee = np.meshgrid(n[::-1], e, indexing="ij")  # rows southwards
    z = surface_depth_m(nn, ee) if values is None else values
    tr = from_origin(E0 - SPACING / 2, N0 + n[-1] + SPACING / 2, SPACING, SPACING)
    with rasterio.open(path, "w", driver="GTiff", height=NX, width=NY, count=1, dtype="float64", crs=crs,
                       transform=tr, nodata=nodata) as dst:
        dst.write(np.asarray(z, dtype=float), 1)


def file_cfg(path: Path, **kw) -> BathymetryFileConfig:
    return BathymetryFileConfig(path=str(path), origin_en_m=(E0, N0), **kw)


def test_geotiff_round_trips_to_the_mesh(tmp_path):
    write_tif(tmp_path / "bed.tif")
    g = read_depth_grid(file_cfg(tmp_path / "bed.tif"))
    np.testing.assert_allclose(g.n_m, np.arange(NX) * SPACING, atol=1e-9)
    np.testing.assert_allclose(g.e_m, np.arange(NY) * SPACING, atol=1e-9)
    nn, ee = np.meshgrid(g.n_m, g.e_m, indexing="ij")
    np.testing.assert_allclose(g.depth_m, surface_depth_m(nn, ee), atol=1e-9)
    seabed = make_seabed(SeabedConfig(kind="file", file=file_cfg(tmp_path / "bed.tif")), np.random.default_rng(0))
    mesh = seabed.terrain_mesh()
    assert mesh.is_watertight
    top = mesh.vertices[mesh.vertices[:, 2] < surface_depth_m(mesh.vertices[:, 0], mesh.vertices[:, 1]) + 1e-9]
    assert len(top) == NX * NY
    # an independent ray cast (trimesh) down at a cell centre hits the surface within the
    # triangle interpolation error of the bowl (curvature 0.004/m over 2 m cells: < 4 mm)
    pts = np.array([[11.0, 13.0], [31.0, 41.0], [70.0, 5.0]])
    locs, idx, _ = mesh.ray.intersects_location(np.c_[pts, np.full(3, -1.0)], np.tile([0.0, 0.0, 1.0], (3, 1)),
                                                multiple_hits=False)
    hit = np.full(3, np.nan)
    hit[idx] = locs[:, 2]
    np.testing.assert_allclose(hit, surface_depth_m(pts[:, 0], pts[:, 1]), atol=4e-3)
    assert seabed.cfg.center_ne_m == (40.0, 35.0) and seabed.cfg.extent_m == 80.0


def test_xyz_and_npy_give_the_same_grid(tmp_path):
    n = np.arange(NX) * SPACING
    e = np.arange(NY) * SPACING
    nn, ee = np.meshgrid(n, e, indexing="ij")
    z = surface_depth_m(nn, ee)
    rows = np.c_[(ee + E0).ravel(), (nn + N0).ravel(), -z.ravel()]  # heights, negative below sea level
    np.savetxt(tmp_path / "bed.xyz", rows[np.random.default_rng(0).permutation(len(rows))], fmt="%.9f")
    g = read_depth_grid(file_cfg(tmp_path / "bed.xyz", values="elevation"))
    np.testing.assert_allclose(g.depth_m, z, atol=1e-8)
    np.testing.assert_allclose(g.n_m, n, atol=1e-8)
    np.save(tmp_path / "bed.npy", z)
    g2 = read_depth_grid(BathymetryFileConfig(path=str(tmp_path / "bed.npy"), spacing_m=SPACING,
                                              origin_ne_m=(-4.0, 6.0), crop_ne_m=((0.0, 40.0), (10.0, 50.0)),
                                              decimate=2))
    np.testing.assert_allclose(g2.n_m, np.arange(0.0, 40.1, 4.0), atol=1e-9)
    np.testing.assert_allclose(g2.e_m, np.arange(10.0, 50.1, 4.0), atol=1e-9)
    np.testing.assert_allclose(g2.depth_m, surface_depth_m(*np.meshgrid(g2.n_m + 4.0, g2.e_m - 6.0, indexing="ij")),
                               atol=1e-9)


def test_nodata_becomes_a_hole(tmp_path):
    n = np.arange(NX) * SPACING
    e = np.arange(NY) * SPACING
    nn, ee = np.meshgrid(n[::-1], e, indexing="ij")
    z = surface_depth_m(nn, ee)
    z[(nn > 60.0) & (ee > 50.0)] = -9999.0
    write_tif(tmp_path / "holed.tif", values=z)
    seabed = make_seabed(SeabedConfig(kind="file", file=file_cfg(tmp_path / "holed.tif")), np.random.default_rng(0))
    assert np.isnan(seabed.depth_grid_m).sum() == ((nn > 60.0) & (ee > 50.0)).sum()
    mesh = seabed.terrain_mesh()
    origins = np.array([[70.0, 60.0, -1.0], [20.0, 20.0, -1.0]])
    hits = mesh.ray.intersects_any(origins, np.tile([0.0, 0.0, 1.0], (2, 1)))
    assert hits.tolist() == [False, True]


def _scenario_file(tmp_path: Path, tif: Path, **survey) -> Path:
    data = yaml.safe_load((scenarios_dir() / "bathymetry_survey.yaml").read_text())
    data["world"]["seabed"]["file"] = {"path": str(tif), "origin_en_m": [E0, N0]}
    data["vehicle"]["initial_pos_ned"] = [10.0, 10.0, 0.3]
    s = data["autonomy"]["guidance"]["survey"]
    s.update({"origin_ne_m": [20.0, 10.0], "length_m": 40.0, "width_m": 16.0, "altitude_m": 3.0, **survey})
    data["autonomy"]["guidance"]["mission"]["safe_depth_max_m"] = 20.0
    p = tmp_path / "scn.yaml"
    p.write_text(yaml.safe_dump(data))
    return p


def test_altimeter_and_dvl_read_the_grid_depth(tmp_path):
    from sim.mission import Mission

    write_tif(tmp_path / "bed.tif")
    scn = load_scenario(_scenario_file(tmp_path, tmp_path / "bed.tif"), ["sensors.fls=null"])
    mission = Mission(scn)
    alt, dvl = mission.sensors["altimeter"], mission.sensors["dvl"]
    for n, e, d in [(30.0, 20.0, 5.0), (50.0, 40.0, 8.0), (12.5, 57.0, 3.0)]:
        mission.physics.reset([n, e, d], [0.0, 0.0, 0.3])
        truth, scene = mission.physics.truth(), mission.physics.scene()
        a = alt.measure(truth, scene, noise=False)
        p = truth.point_ned(alt.mount.pos_body_m)
        assert a.valid
        assert a.altitude_m == pytest.approx(surface_depth_m(p[0], p[1]) - p[2], abs=4e-3)
        v = dvl.measure(truth, scene, noise=False)
        q = truth.point_ned(dvl.mount.pos_body_m)
        assert v.valid
        # the DVL's footprint plane: the bowl bends away from it by at most c r^2 / 2 (r ~ tan30 * alt)
        r = np.tan(np.deg2rad(30.0)) * (surface_depth_m(q[0], q[1]) - q[2])
        assert v.altitude_m == pytest.approx(surface_depth_m(q[0], q[1]) - q[2], abs=0.004 * r**2 + 0.01)


def test_wrong_crs_all_nodata_and_outside_survey_are_refused(tmp_path, capsys):
    from sim.cli import main

    write_tif(tmp_path / "geo.tif", crs="EPSG:4326")
    with pytest.raises(ScenarioError, match=r"world\.seabed\.file\.path: .*geo\.tif: CRS EPSG:4326 is not a projected"):
        load_scenario(_scenario_file(tmp_path, tmp_path / "geo.tif"))
    write_tif(tmp_path / "empty.tif", values=np.full((NX, NY), -9999.0))
    with pytest.raises(ScenarioError, match=r"world\.seabed\.file\.path: .*empty\.tif: holds no valid depth"):
        load_scenario(_scenario_file(tmp_path, tmp_path / "empty.tif"))
    write_tif(tmp_path / "bed.tif")
    scn = _scenario_file(tmp_path, tmp_path / "bed.tif", length_m=120.0)  # legs run past the grid's 80 m
    assert main(["validate", str(scn)]) == 2
    err = capsys.readouterr().err
    assert "autonomy.guidance.survey" in err and "outside the bathymetry" in err and err.count("\n") == 1  # one problem: one line
    with pytest.raises(BathymetryError, match=r"world\.seabed\.file\.origin_en_m: required"):
        read_depth_grid(BathymetryFileConfig(path=str(tmp_path / "bed.tif")))


def test_shipped_sample_matches_its_documented_model():
    import importlib.util

    spec = importlib.util.spec_from_file_location("mk", Path(__file__).resolve().parents[3] / "scripts" /
                                                  "make_bathymetry_sample.py")
    mk = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mk)
    scn = load_scenario("bathymetry_survey")
    g = read_depth_grid(scn.world.seabed.file)
    nn, ee = np.meshgrid(g.n_m, g.e_m, indexing="ij")
    ok = np.isfinite(g.depth_m)
    np.testing.assert_allclose(g.depth_m[ok], mk.sample_depth_m(nn, ee)[ok], atol=1e-5)  # float32 file
    np.testing.assert_array_equal(~ok, nn + ee > 290.0)
