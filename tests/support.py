"""Helpers the tests share (synthetic truths and seabeds, sensor suites, stand-ins, CLI runners):
one module, so that no test module imports another."""

from __future__ import annotations

import importlib.util
import json
import os
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from autonomy.frames import euler_rate_matrix, rot_from_euler
from autonomy.sonar_geometry import FanGeometry
from sim.cli import main
from sim.dynamics.truth import VehicleTruth
from sim.sensors.base import SceneView
from sim.sensors.nav_noise import nav_noise_model
from sim.sensors.raycast import RayHits


def _wiggle_pos(t):
    """Closed-form NED position (3,) and its first and second derivatives."""
    w1, w2, w3 = 0.21, 0.13, 0.07
    pos = np.array([0.4 * t + 2.0 * np.sin(w1 * t), 3.0 * (1.0 - np.cos(w2 * t)), 2.0 + 0.5 * np.sin(w3 * t)])
    vel = np.array([0.4 + 2.0 * w1 * np.cos(w1 * t), 3.0 * w2 * np.sin(w2 * t), 0.5 * w3 * np.cos(w3 * t)])
    acc = np.array([-2.0 * w1**2 * np.sin(w1 * t), 3.0 * w2**2 * np.cos(w2 * t), -0.5 * w3**2 * np.sin(w3 * t)])
    return pos, vel, acc


def _wiggle_rpy(t):
    rpy = np.array([0.08 * np.sin(0.5 * t), 0.06 * np.sin(0.3 * t + 0.4), 0.3 + 0.05 * t])
    rpy_dot = np.array([0.04 * np.cos(0.5 * t), 0.018 * np.cos(0.3 * t + 0.4), 0.05])
    return rpy, rpy_dot


def _omega(t):
    rpy, rpy_dot = _wiggle_rpy(t)
    return np.linalg.solve(euler_rate_matrix(rpy[0], rpy[1]), rpy_dot)


SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"
#: The real ARIS 3000 frames (the Marine Debris water-tank development split) beside the
#: checkout, or where ``AUVSIM_REAL_FLS_DIR`` says; tests that need them skip when absent.
REAL_WATERTANK_DIR = Path(os.environ.get("AUVSIM_REAL_FLS_DIR", Path(__file__).resolve().parents[1].parent / "shared"
                                         / "data" / "marine-debris-watertank-dev"))


class PlaneCaster:
    """Rays against one infinite plane through ``point_ned`` with unit ``normal_ned`` facing
    the vehicle (a flat seabed at depth D is point [0, 0, D], normal [0, 0, -1])."""

    def __init__(self, point_ned, normal_ned, reflectivity: float = 0.3):
        self.point = np.asarray(point_ned, float)
        n = np.asarray(normal_ned, float)
        self.normal = n / np.linalg.norm(n)
        self.reflectivity = reflectivity

    def cast(self, origin_ned, dirs_ned, max_range_m):
        dirs = np.atleast_2d(np.asarray(dirs_ned, float))
        denom = dirs @ self.normal
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = ((self.point - origin_ned) @ self.normal) / denom
        hit = (denom < 0.0) & (dist > 0.0) & (dist <= max_range_m)
        return RayHits(
            dist_m=np.where(hit, dist, np.inf),
            normal_ned=np.where(hit[:, None], self.normal, 0.0),
            reflectivity=np.where(hit, self.reflectivity, 0.0),
            object_id=np.where(hit, -1, -2).astype(np.int64),
        )


def flat_seabed(depth_m: float) -> PlaneCaster:
    return PlaneCaster([0.0, 0.0, depth_m], [0.0, 0.0, -1.0])


def wiggle_truth(t: float) -> VehicleTruth:
    """Closed-form 6-DOF trajectory (vehicle sways, rolls, pitches and turns) at time ``t``."""
    pos, vel_ned, acc_ned = _wiggle_pos(t)
    rpy, _ = _wiggle_rpy(t)
    R = rot_from_euler(*rpy)
    omega = _omega(t)
    v_body = R.T @ vel_ned
    v_dot = R.T @ acc_ned - np.cross(omega, v_body)  # d/dt (R^T v_n), R_dot = R S(omega)
    h = 1e-5
    omega_dot = (_omega(t + h) - _omega(t - h)) / (2 * h)
    return VehicleTruth(
        t_s=float(t), pos_ned=pos, R_nb=R, rpy_rad=rpy, nu=np.concatenate([v_body, omega]),
        nu_dot=np.concatenate([v_dot, omega_dot]), current_ned=np.zeros(3),
    )


def static_truth(pos_ned=(0.0, 0.0, 1.0), rpy_rad=(0.0, 0.0, 0.0), t_s: float = 0.0) -> VehicleTruth:
    rpy = np.asarray(rpy_rad, float)
    return VehicleTruth(t_s=t_s, pos_ned=np.asarray(pos_ned, float), R_nb=rot_from_euler(*rpy), rpy_rad=rpy,
                        nu=np.zeros(6), nu_dot=np.zeros(6), current_ned=np.zeros(3))


def survey_truths(dt_s: float = 0.1, speed_mps: float = 0.5, leg_s: float = 120.0, n_legs: int = 4,
                  surface_s: float = 30.0, depth_m: float = 2.0, yaw0_rad: float = 0.3) -> list[VehicleTruth]:
    """Lawnmower-like run sampled every ``dt_s``: a straight run at the surface, a dive,
    ``n_legs`` legs joined by 180 deg turns (0.1 rad/s), then a climb back to the surface.
    Body velocity [u, 0, w], small roll/pitch oscillation; position integrated with the
    trapezoid rule on a 10x finer grid."""
    turn_rate = 0.1
    turn_s = np.pi / turn_rate
    dive_s = 40.0
    schedule = surface_s + dive_s + n_legs * leg_s + (n_legs - 1) * turn_s + dive_s + surface_s
    sub = 10
    t = np.arange(0.0, schedule + 1e-9, dt_s / sub)

    # yaw rate profile: alternate left/right turns between legs
    yaw_rate = np.zeros_like(t)
    start = surface_s + dive_s + leg_s
    for k in range(n_legs - 1):
        in_turn = (t >= start) & (t < start + turn_s)
        yaw_rate[in_turn] = turn_rate * (1 if k % 2 == 0 else -1)
        start += turn_s + leg_s
    yaw = yaw0_rad + np.concatenate([[0.0], np.cumsum(0.5 * (yaw_rate[1:] + yaw_rate[:-1]) * np.diff(t))])

    # vertical: smooth dive and climb (w in NED), 0 elsewhere
    def bump(tt, t0, dur, dz):
        s = np.clip((tt - t0) / dur, 0.0, 1.0)
        inside = (tt > t0) & (tt < t0 + dur)
        return np.where(inside, dz / dur * (1.0 - np.cos(2 * np.pi * s)), 0.0)

    d_dot = bump(t, surface_s, dive_s, depth_m) + bump(t, schedule - surface_s - dive_s, dive_s, -depth_m)
    roll = np.radians(0.5) * np.sin(0.4 * t)
    pitch = np.radians(0.5) * np.sin(0.25 * t + 1.0)
    roll_dot = np.radians(0.5) * 0.4 * np.cos(0.4 * t)
    pitch_dot = np.radians(0.5) * 0.25 * np.cos(0.25 * t + 1.0)

    vel_ned = np.stack([speed_mps * np.cos(yaw), speed_mps * np.sin(yaw), d_dot], axis=1)
    pos = np.concatenate([[[0.0, 0.0, 0.0]], np.cumsum(0.5 * (vel_ned[1:] + vel_ned[:-1]) * np.diff(t)[:, None], axis=0)])
    acc_ned = np.gradient(vel_ned, t, axis=0)

    truths = []
    for i in range(0, len(t), sub):
        rpy = np.array([roll[i], pitch[i], yaw[i]])
        R = rot_from_euler(*rpy)
        omega = np.linalg.solve(euler_rate_matrix(roll[i], pitch[i]), [roll_dot[i], pitch_dot[i], yaw_rate[i]])
        v_body = R.T @ vel_ned[i]
        v_dot = R.T @ acc_ned[i] - np.cross(omega, v_body)
        truths.append(VehicleTruth(t_s=float(t[i]), pos_ned=pos[i].copy(), R_nb=R, rpy_rad=rpy,
                                   nu=np.concatenate([v_body, omega]), nu_dot=np.concatenate([v_dot, np.zeros(3)]),
                                   current_ned=np.zeros(3)))
    return truths


NAV_MOUNTS = {"imu": np.zeros(3), "dvl": np.array([0.15, 0.0, 0.25]), "depth": np.array([-0.2, 0.0, 0.0]),
          "altimeter": np.array([0.2, 0.0, 0.25]), "gps": np.array([-0.1, 0.0, -0.4])}


FLAT_SEABED_6M = flat_seabed(6.0)


SURVEY_DT_S = 0.2  # IMU, DVL and depth every step, GPS every 5th


SURVEY_TRUTHS = survey_truths(dt_s=SURVEY_DT_S, leg_s=80.0, n_legs=2)


NAV_NOISE = nav_noise_model()  # the filter's model of the default sensors


def fly_filters(filters, sensors, truths, every: int = 1, noise: bool = True):
    """Feed every filter the same sensor messages; yield (truth, [estimate...]) every ``every`` steps."""
    for k, tr in enumerate(truths):
        msgs = [sensors["imu"].measure(tr, noise=noise),
                sensors["dvl"].measure(tr, SceneView(0.0, FLAT_SEABED_6M), noise=noise),
                sensors["depth"].measure(tr, noise=noise)]
        gps = sensors["gps"].measure(tr, noise=noise) if k % 5 == 0 else None
        for f in filters:
            f.on_imu(msgs[0])
            f.on_dvl(msgs[1])
            f.on_depth(msgs[2])
            if gps is not None:
                f.on_gps(gps)
        if k % every == 0:
            yield tr, [f.estimate() for f in filters]


@dataclass(frozen=True)
class SceneObj:
    id: int
    name: str
    class_name: str
    is_target: bool
    centroid_ned: np.ndarray


PIPELINE_OVERRIDES = ["autonomy.guidance.mission.start_delay_s=0", "vehicle.initial_pos_ned=[0.0,0.0,2.0]", "duration_s=3.0"]


def pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:  # a zombie is not running
        return f.read().rsplit(")", 1)[1].split()[0] != "Z"


class FakeRerunStream:
    """Stands in for ``rr.RecordingStream``: keeps (entity, archetype) per log call and the
    columns of each ``send_columns``."""

    def __init__(self) -> None:
        self.logs: dict[str, list] = defaultdict(list)
        self.columns: dict[str, list] = defaultdict(list)  # entity -> [(indexes, columns)] per send_columns
        self.flushes: list[float] = []  # timeout_sec of each flush

    def save(self, path) -> None:
        pass

    def set_time(self, *args, **kwargs) -> None:
        pass

    def log(self, entity: str, archetype, static: bool = False) -> None:
        self.logs[entity].append(archetype)

    def send_columns(self, entity: str, indexes, columns) -> None:
        self.columns[entity].append((indexes, columns))

    def flush(self, timeout_sec: float = 1e38) -> None:
        self.flushes.append(timeout_sec)

    def disconnect(self) -> None:
        pass


def image_strips(arch) -> list[np.ndarray]:
    return [np.asarray(s, dtype=float) for s in arch.strips.as_arrow_array().to_pylist()]


def load_script(name: str):
    spec = importlib.util.spec_from_file_location(name, SCRIPTS / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def script_refusal(mod, argv, capsys, *culprits: str) -> str:
    capsys.readouterr()
    code = mod.main(argv)
    out = capsys.readouterr()
    assert code == 2, out.err
    assert "Traceback" not in out.err and out.out == ""
    lines = out.err.strip().splitlines()
    assert len(lines) == 1, out.err
    for c in culprits:
        assert c in lines[0], lines[0]
    return lines[0]


def run_cli(argv, capsys) -> tuple[int, str]:
    capsys.readouterr()  # only this command's output
    code = main(argv)
    err = capsys.readouterr().err
    return code, err


def assert_clean_error(code: int, err: str, *culprits: str) -> None:
    assert code == 2, err
    assert "Traceback" not in err, err
    assert err.strip(), "no message"
    first = err.strip().splitlines()[0]
    for c in culprits:
        assert c in err, f"{c!r} not named in: {err}"
    assert first.startswith("auvsim "), first


# -- hand-made FLS dataset folders (COCO file + PNG fans), written in milliseconds instead of rendered
FAN_DATASET_CLASSES = ("opi", "rock", "debris")


def write_fan_dataset(folder: Path, n_images: int = 4, fan_hw: tuple[int, int] = (477, 894),
                      labelled: tuple[str, ...] = ("opi", "rock"), grey: int = 40) -> Path:
    """``n_images`` uniform ``grey`` fans of ``fan_hw`` (height, width), each with one labelled
    box per class in ``labelled`` (nothing drawn there); categories: :data:`FAN_DATASET_CLASSES`."""
    (folder / "images").mkdir(parents=True)
    h, w = fan_hw
    g = FanGeometry.fit(w, h, 1.0, 30.0, np.deg2rad(130.0))
    images, anns = [], []
    for i in range(n_images):
        name = f"images/{i:06d}.png"
        cv2.imwrite(str(folder / name), np.full((h, w), grey, np.uint8))
        images.append({"id": i, "file_name": name, "width": w, "height": h, "t_s": 0.0,
                       "fan_geometry": {"width_px": g.width_px, "height_px": g.height_px, "range_min_m": g.range_min_m,
                                        "range_max_m": g.range_max_m, "fov_rad": g.fov_rad, "m_per_px": g.m_per_px,
                                        "apex_x_px": g.apex_x_px, "apex_y_px": g.apex_y_px}})
        for k, cls in enumerate(labelled):
            x, y = 0.3 * w + 0.2 * w * k, 0.4 * h
            anns.append({"id": len(anns) + 1, "image_id": i, "category_id": FAN_DATASET_CLASSES.index(cls) + 1,
                         "bbox": [x, y, 0.05 * w, 0.05 * h], "area": 0.0025 * w * h, "iscrowd": 0,
                         "attributes": {"range_m": 15.0}})
    cats = [{"id": k + 1, "name": n} for k, n in enumerate(FAN_DATASET_CLASSES)]
    (folder / "annotations.json").write_text(json.dumps({"images": images, "annotations": anns, "categories": cats}))
    return folder


# -- hand-made folders in the watertank layout (images/, boxes/*.xml, masks/) of real labelled frames
#: The fan of the hand-made watertank frames: an ARIS 3000 window of 0.7-2.9 m, 30 deg, on the
#: 320 x 480 px grid of the Marine Debris set.
WATERTANK_GEOM = FanGeometry(320, 480, 0.7, 2.9, np.deg2rad(30.0), 0.0050, 159.4, 602.5)


def watertank_box_xml(boxes: list[tuple[str, tuple[int, int, int, int]]]) -> str:
    """A box file of the watertank layout: one ``object`` per (class, (x, y, w, h) px)."""
    objs = "".join(f"<object><name>{c}</name><bndbox><x>{x}</x><y>{y}</y><w>{w}</w><h>{h}</h></bndbox></object>"
                   for c, (x, y, w, h) in boxes)
    return f"<annotation><filename>f.png</filename>{objs}</annotation>"


def write_watertank_folder(root: Path, frames: list[list[tuple[str, tuple[int, int, int, int]]]],
                           seed: int = 0) -> Path:
    """One frame per entry of ``frames`` (its boxes: class and (x, y, w, h) px): speckle inside
    :data:`WATERTANK_GEOM`'s fan, black outside, each box filled brighter, its class id in the
    mask; names ``frame-0.png`` ... in natural order."""
    from sim.dataset.real_frames import MARINE_DEBRIS_CLASSES

    ids = {n: k for k, n in MARINE_DEBRIS_CLASSES.items()}
    g = WATERTANK_GEOM
    yy, xx = np.mgrid[0:g.height_px, 0:g.width_px]
    r, a = g.pixel_to_polar(xx, yy)
    inside = g.inside(r, a)
    rng = np.random.default_rng(seed)
    for sub in ("images", "boxes", "masks"):
        (root / sub).mkdir(parents=True, exist_ok=True)
    for i, boxes in enumerate(frames):
        img = np.clip(rng.exponential(30.0, inside.shape) + 1, 1, 255)
        mask = np.zeros(inside.shape, np.uint8)
        for c, (x, y, w, h) in boxes:
            img[y:y + h, x:x + w] = 220
            mask[y:y + h, x:x + w] = ids[c]
        cv2.imwrite(str(root / "images" / f"frame-{i}.png"), np.where(inside, img, 0).astype(np.uint8))
        cv2.imwrite(str(root / "masks" / f"frame-{i}.png"), mask)
        (root / "boxes" / f"frame-{i}.xml").write_text(watertank_box_xml(boxes))
    return root


def random_dirs(n: int, seed: int = 0) -> np.ndarray:
    """(n, 3) unit ray directions, all with a forward (+x) component of at least about 0.5."""
    v = np.random.default_rng(seed).normal(size=(n, 3))
    v[:, 0] = np.abs(v[:, 0]) + 0.5
    return v / np.linalg.norm(v, axis=1, keepdims=True)
