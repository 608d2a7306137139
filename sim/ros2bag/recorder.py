"""Mission observer writing a ROS 2 bag (rosbag2 folder, MCAP storage) as the mission runs.

Topics (header stamps and bag log times are simulation time):

=========================== ================================== =============================
topic                       type                               rate
=========================== ================================== =============================
/tf_static                  tf2_msgs/TFMessage                 at start (+ once per sonar)
/tf                         tf2_msgs/TFMessage                 autonomy rate: map->base_link_truth,
                                                               odom->base_link (estimate)
/auvsim/truth/odometry      nav_msgs/Odometry                  autonomy rate (map, base_link_truth)
/auvsim/truth/pose          geometry_msgs/PoseStamped          autonomy rate (map)
/auvsim/nav/odometry        nav_msgs/Odometry                  autonomy rate (odom, base_link)
/auvsim/<imu>               sensor_msgs/Imu                    sensor rate
/auvsim/<depth>             sensor_msgs/FluidPressure          sensor rate
/auvsim/<altimeter>         sensor_msgs/Range                  sensor rate
/auvsim/<dvl>               marine_acoustic_msgs/Dvl           sensor rate
/auvsim/<fls>/image         marine_acoustic_msgs/ProjectedSonarImage  sensor rate / fls_every
/auvsim/<fls>/detections    vision_msgs/Detection2DArray       per processed frame
/auvsim/world_model         visualization_msgs/MarkerArray     per processed frame
/auvsim/<vehicle>/truth/odometry  nav_msgs/Odometry            autonomy rate (map, <vehicle>_truth)
=========================== ================================== =============================

``<name>`` is the sensor's entry name in the scenario, ``<vehicle>`` an extra vehicle's
(``vehicles:``, e.g. the sea trial's buoy; ``/tf`` carries map->``<vehicle>_truth`` too). Messages of other sensors (GPS,
USBL, ...) are not exported.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from autonomy.frames import R_FLU_FRD, enu_from_ned, flu_from_frd, rot_enu_flu, rot_from_euler
from autonomy.navigation.dvl_geometry import janus_beam_dirs_body
from sim.events.records import MissionInfo, MissionSummary, ObserverBase, PerceptionResult, StepRecord
from sim.ros2bag.ros_messages import RosConverter, altimeter_frame_in_flu, sonar_msg_frame_in_flu, stamp_ns
from sim.ros2bag.typestore import make_typestore

MAP, ODOM, BASE, BASE_TRUTH, BASE_FRD = "map", "odom", "base_link", "base_link_truth", "base_link_frd"
TARGET_CLASS = "target"


class RosbagRecorder(ObserverBase):
    """Writes the mission into the rosbag2 folder ``path`` (must not exist yet).

    Args:
        path: the bag folder to create (``<run>/rosbag``).
        fls_every: export every n-th frame of each sonar (1 = all; an M900-130 frame is ~0.8 MB).

    Raises:
        ImportError: rosbags is not installed.
        FileExistsError: ``path`` exists (raised by :meth:`on_start`).
    """

    sonar_truth = False  # writes the frames' images, not their ground truth

    def __init__(self, path: Path, *, fls_every: int = 1) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer

        self.path = Path(path)
        self.fls_every = max(int(fls_every), 1)
        self.store = make_typestore()
        self.conv = RosConverter(self.store)
        self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._conns: dict[str, Any] = {}
        self._handlers: dict[str, Any] = {}
        self._n_frames: dict[str, int] = {}
        self._sonar_tf_sent: set[str] = set()
        self.counts: dict[str, int] = {}

    # -- writing -----------------------------------------------------------------------
    def _write(self, topic: str, msgtype: str, t_s: float, msg: Any) -> None:
        conn = self._conns.get(topic)
        if conn is None:
            conn = self._conns[topic] = self._writer.add_connection(topic, msgtype, typestore=self.store)
        self._writer.write(conn, stamp_ns(t_s), self.store.serialize_cdr(msg, msgtype))
        self.counts[topic] = self.counts.get(topic, 0) + 1

    def _tf_static(self, t_s: float, transforms: list) -> None:
        self._write("/tf_static", "tf2_msgs/msg/TFMessage", t_s, self.conv.tf_message(transforms))

    # -- observer protocol -------------------------------------------------------------
    def on_start(self, info: MissionInfo) -> None:
        from scenarios.vehicle_params import load_vehicle_params

        self._writer.open()
        scn, c = info.scenario, self.conv
        params = load_vehicle_params(scn.vehicle)
        static = [c.transform(0.0, MAP, ODOM, np.zeros(3), np.eye(3)),
                  c.transform(0.0, BASE, BASE_FRD, np.zeros(3), R_FLU_FRD)]
        for name, kind in info.sensors.items():
            cfg = scn.sensors[name]
            topic = f"/auvsim/{name}"
            if kind == "imu":
                self._handlers[name] = lambda m, t=topic: self._write(
                    t, "sensor_msgs/msg/Imu", m.t_s, c.imu(m, BASE))
            elif kind == "depth":
                rho, g = float(params.rho_kgpm3), float(params.gravity_mps2)
                self._handlers[name] = lambda m, t=topic, rho=rho, g=g: self._write(
                    t, "sensor_msgs/msg/FluidPressure", m.t_s, c.fluid_pressure(m, BASE, rho, g))
            elif kind == "altimeter":
                frame = f"{name}_link"
                mount = info.sensor_mounts[name]
                static.append(c.transform(0.0, BASE, frame, flu_from_frd(mount.pos_body_m),
                                          altimeter_frame_in_flu(mount.R_bs)))
                self._handlers[name] = lambda m, t=topic, f=frame, cfg=cfg: self._write(
                    t, "sensor_msgs/msg/Range", m.t_s, c.range_altimeter(m, f, cfg.min_range_m, cfg.max_range_m))
            elif kind == "dvl":
                # the DVL measures its transducer's velocity in body FRD axes: the frame sits at
                # the mount with the body's FRD axes; its beams are the mount-rotated Janus fan
                frame = f"{name}_link"
                mount = info.sensor_mounts[name]
                dirs = janus_beam_dirs_body(np.deg2rad(cfg.beam_angle_deg), np.deg2rad(cfg.beam_azimuth_offset_deg))
                dirs = dirs @ mount.R_bs.T
                static.append(c.transform(0.0, BASE, frame, flu_from_frd(mount.pos_body_m), R_FLU_FRD))
                self._handlers[name] = lambda m, t=topic, d=dirs, f=frame: self._write(
                    t, "marine_acoustic_msgs/msg/Dvl", m.t_s, c.dvl(m, f, d))
            elif kind == "fls":
                from scenarios.fls_presets import resolve_geometry

                geo = resolve_geometry(cfg)
                self._handlers[name] = self._sonar_handler(name, geo)
        self._tf_static(0.0, static)

    def _sonar_handler(self, name: str, geo: Any):
        """Writer of one FLS's images (ping info from its resolved preset ``geo``:
        :class:`scenarios.fls_presets.FlsGeometry`) and perception results."""
        c, frame = self.conv, f"{name}_link"
        azimuths_rad, bins_m = geo.beam_azimuths_rad(), geo.bin_centres_m()
        ping = dict(frequency_hz=geo.frequency_hz, sound_speed_mps=geo.sound_speed_mps,
                    tx_beamwidth_rad=geo.vertical_beamwidth_rad, rx_beamwidth_rad=geo.beamwidth_az_rad)

        def handle(msg: Any) -> None:
            if isinstance(msg, PerceptionResult):
                self._write(f"/auvsim/{name}/detections", "vision_msgs/msg/Detection2DArray", msg.t_s,
                            c.detections(msg, frame))
                self._write("/auvsim/world_model", "visualization_msgs/msg/MarkerArray", msg.t_s,
                            c.world_model_markers(msg.t_s, msg.world_objects, MAP, TARGET_CLASS))
                return
            fls_frame = getattr(msg, "frame", None)
            if fls_frame is None:
                return
            if name not in self._sonar_tf_sent:
                self._sonar_tf_sent.add(name)
                pos, R = sonar_msg_frame_in_flu(fls_frame.mount_pos_body_m, fls_frame.mount_rpy_rad)
                self._tf_static(fls_frame.t_s, [c.transform(fls_frame.t_s, BASE, frame, pos, R)])
            k = self._n_frames.get(name, 0)
            self._n_frames[name] = k + 1
            if k % self.fls_every == 0:
                self._write(f"/auvsim/{name}/image", "marine_acoustic_msgs/msg/ProjectedSonarImage", fls_frame.t_s,
                            c.projected_sonar_image(fls_frame, frame, azimuths_rad, bins_m, **ping))

        return handle

    def on_step(self, r: StepRecord) -> None:
        c, tr, nav = self.conv, r.truth, r.nav
        R_nav = rot_from_euler(*nav.rpy_rad)
        pos_true_enu_tf = c.transform(r.t_s, MAP, BASE_TRUTH, enu_from_ned(tr.pos_ned), rot_enu_flu(tr.R_nb))
        pos_nav_enu_tf = c.transform(r.t_s, ODOM, BASE, enu_from_ned(nav.pos_ned), rot_enu_flu(R_nav))
        others = [(name, f"{name}_truth", o) for name, o in r.others.items()]
        other_tfs = [c.transform(r.t_s, MAP, frame, enu_from_ned(o.pos_ned), rot_enu_flu(o.R_nb))
                     for _, frame, o in others]
        self._write("/tf", "tf2_msgs/msg/TFMessage", r.t_s, c.tf_message([pos_true_enu_tf, pos_nav_enu_tf, *other_tfs]))
        for name, frame, o in others:
            self._write(f"/auvsim/{name}/truth/odometry", "nav_msgs/msg/Odometry", r.t_s,
                        c.odometry(r.t_s, o.pos_ned, o.R_nb, o.nu[:3], o.nu[3:], MAP, frame))
        self._write("/auvsim/truth/odometry", "nav_msgs/msg/Odometry", r.t_s,
                    c.odometry(r.t_s, tr.pos_ned, tr.R_nb, tr.nu[:3], tr.nu[3:], MAP, BASE_TRUTH))
        self._write("/auvsim/truth/pose", "geometry_msgs/msg/PoseStamped", r.t_s,
                    c.pose_stamped(r.t_s, tr.pos_ned, tr.R_nb, MAP))
        self._write("/auvsim/nav/odometry", "nav_msgs/msg/Odometry", r.t_s,
                    c.odometry(r.t_s, nav.pos_ned, R_nav, nav.vel_body_mps, nav.rate_body_radps, ODOM, BASE,
                               cov_pos_ned_m2=nav.cov_pos_ned, var_yaw_rad2=nav.cov_yaw_rad2))

    def on_message(self, name: str, msg: Any) -> None:
        handler = self._handlers.get(name)
        if handler is not None:
            handler(msg)

    def on_end(self, summary: MissionSummary) -> None:
        self._writer.close()

