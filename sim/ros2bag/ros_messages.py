"""Conversion of auvsim records and sensor messages into ROS 2 messages (rosbags objects).

Frames follow REP 103 / REP 105: the world is ENU (``map``; ``odom`` coincides with it),
the vehicle body is FLU (``base_link`` for the navigation estimate, ``base_link_truth``
for the true pose). The NED/FRD -> ENU/FLU conversion is done in :mod:`autonomy.frames`
(``enu_from_ned``, ``flu_from_frd``, ``rot_enu_flu``) and nowhere else. Sensor frames:

* ``base_link_frd``: the FRD body axes (``base_link`` turned by pi about x).
* ``<dvl>_link``: at the DVL's mount, the FRD body axes: the DVL measures its transducer's
  velocity over ground in body axes (DVL convention: z along the pointing direction, down;
  x forward).
* ``<altimeter>_link``: at the altimeter's mount, x along the echo-sounder beam (straight
  down for an aligned mount), as ``sensor_msgs/Range``.
* ``<fls>_link``: the ``ProjectedSonarImage`` frame, z along the sonar boresight, x up in
  the fan's vertical plane, y to starboard.

Header stamps are simulation time (seconds since the start of the run).
"""

from __future__ import annotations

import math
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from autonomy.frames import (
    R_FLU_FRD, cov_enu_from_ned, enu_from_ned, flu_from_frd, quat_from_rot, quat_xyzw, rot_enu_flu,
    rot_from_euler,
)
from autonomy.sonar_frame import ray_directions_sonar, sonar_to_body_rotation
from sim.ros2bag.builders import build

FloatArray = NDArray[np.float64]

#: (3, 3) ProjectedSonarImage axes (x up, y starboard, z boresight) -> sonar frame (x
#: boresight, y starboard, z down): columns are the message axes in the sonar frame.
R_SONAR_SONARMSG: FloatArray = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
#: (3, 3) altimeter_link (x down the beam) -> FLU body: a +90 deg pitch about y (left).
R_FLU_ALTIMETER: FloatArray = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
ATMOSPHERE_PA = 101325.0


def altimeter_frame_in_flu(R_bs: ArrayLike) -> FloatArray:
    """(3, 3) ``<altimeter>_link`` -> FLU body rotation for a mount whose sensor axes turn
    into the body's FRD axes by ``R_bs`` (the echo sounder looks along its sensor z, down):
    x of the link is the beam. Equals :data:`R_FLU_ALTIMETER` for an aligned mount."""
    return R_FLU_FRD @ np.asarray(R_bs, dtype=float) @ R_FLU_FRD @ R_FLU_ALTIMETER


def _per_beam(value_rad: float | None, n_beams: int) -> NDArray[np.float32]:
    """``float32[]`` of ``n_beams`` copies of ``value_rad``; empty when None (unknown)."""
    if value_rad is None:
        return np.zeros(0, dtype=np.float32)
    return np.full(n_beams, value_rad, dtype=np.float32)


def stamp_ns(t_s: float) -> int:
    """Simulation time (s) as integer nanoseconds (bag log time and header stamp)."""
    return int(round(float(t_s) * 1e9))


class RosConverter:
    """Builds the ROS messages of one run from a rosbags type store.

    Args:
        store: rosbags ``Typestore`` with the standard and the shipped marine/vision types.
    """

    def __init__(self, store: Any) -> None:
        self.store = store
        T = store.types
        self._Time = T["builtin_interfaces/msg/Time"]
        self._Header = T["std_msgs/msg/Header"]
        self._Vector3 = T["geometry_msgs/msg/Vector3"]
        self._Point = T["geometry_msgs/msg/Point"]
        self._Quaternion = T["geometry_msgs/msg/Quaternion"]
        self._Pose = T["geometry_msgs/msg/Pose"]
        self._beam_cache: dict[tuple[bytes, bytes], tuple[list, np.ndarray]] = {}

    # -- primitives ------------------------------------------------------------------
    def header(self, t_s: float, frame_id: str) -> Any:
        ns = stamp_ns(t_s)
        return self._Header(stamp=self._Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000), frame_id=frame_id)

    def vector3(self, v: ArrayLike) -> Any:
        x, y, z = np.asarray(v, dtype=float).reshape(3).tolist()
        return self._Vector3(x=x, y=y, z=z)

    def _sonar_beams(self, beam_azimuths_rad: ArrayLike, bin_centres_m: ArrayLike) -> tuple[list, np.ndarray]:
        """The beam direction vectors (message frame) and float32 ranges of one sonar
        geometry, built once per geometry: they are the same in every frame."""
        az = np.ascontiguousarray(beam_azimuths_rad, dtype=float)
        bins = np.ascontiguousarray(bin_centres_m, dtype=float)
        key = (az.tobytes(), bins.tobytes())
        hit = self._beam_cache.get(key)
        if hit is None:
            dirs = ray_directions_sonar(az, 0.0) @ R_SONAR_SONARMSG  # sonar -> message axes
            V = self._Vector3
            hit = self._beam_cache[key] = ([V(x=float(x), y=float(y), z=float(z)) for x, y, z in dirs.tolist()],
                                           bins.astype(np.float32))
        return hit

    def point(self, p: ArrayLike) -> Any:
        x, y, z = np.asarray(p, dtype=float).reshape(3).tolist()
        return self._Point(x=x, y=y, z=z)

    def quaternion(self, R: ArrayLike) -> Any:
        x, y, z, w = np.asarray(quat_xyzw(quat_from_rot(R)), dtype=float).tolist()
        return self._Quaternion(x=x, y=y, z=z, w=w)

    def pose(self, pos: ArrayLike, R: ArrayLike) -> Any:
        return self._Pose(position=self.point(pos), orientation=self.quaternion(R))

    def transform(self, t_s: float, parent: str, child: str, translation: ArrayLike, R: ArrayLike) -> Any:
        """``geometry_msgs/TransformStamped`` of ``child`` in ``parent`` (R: child -> parent axes)."""
        T = self.store.types
        q = self.quaternion(R)
        return T["geometry_msgs/msg/TransformStamped"](
            header=self.header(t_s, parent), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](translation=self.vector3(translation), rotation=q))

    def tf_message(self, transforms: list) -> Any:
        return self.store.types["tf2_msgs/msg/TFMessage"](transforms=transforms)

    # -- vehicle state -----------------------------------------------------------------
    def odometry(self, t_s: float, pos_ned: ArrayLike, R_nb: ArrayLike, vel_body_mps: ArrayLike,
                 rate_body_radps: ArrayLike, frame_id: str, child_frame_id: str,
                 cov_pos_ned_m2: ArrayLike | None = None, var_yaw_rad2: float | None = None) -> Any:
        """``nav_msgs/Odometry``: pose in ``frame_id`` (ENU), twist in ``child_frame_id`` (FLU).

        The pose covariance holds the position block (ENU, m^2) and the yaw variance (rad^2)
        when given; unknown entries are 0.
        """
        cov = np.zeros((6, 6))
        if cov_pos_ned_m2 is not None:
            cov[:3, :3] = cov_enu_from_ned(cov_pos_ned_m2)
        if var_yaw_rad2 is not None:
            cov[5, 5] = float(var_yaw_rad2)  # ENU yaw = pi/2 - NED yaw: same variance
        T = self.store.types
        return T["nav_msgs/msg/Odometry"](
            header=self.header(t_s, frame_id), child_frame_id=child_frame_id,
            pose=T["geometry_msgs/msg/PoseWithCovariance"](
                pose=self.pose(enu_from_ned(pos_ned), rot_enu_flu(R_nb)), covariance=cov.ravel()),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](
                twist=T["geometry_msgs/msg/Twist"](linear=self.vector3(flu_from_frd(vel_body_mps)),
                                                   angular=self.vector3(flu_from_frd(rate_body_radps))),
                covariance=np.zeros(36)))

    def pose_stamped(self, t_s: float, pos_ned: ArrayLike, R_nb: ArrayLike, frame_id: str) -> Any:
        """``geometry_msgs/PoseStamped`` of a body (FRD -> NED ``R_nb``) in ENU ``frame_id``."""
        return self.store.types["geometry_msgs/msg/PoseStamped"](
            header=self.header(t_s, frame_id), pose=self.pose(enu_from_ned(pos_ned), rot_enu_flu(R_nb)))

    # -- sensors -----------------------------------------------------------------------
    def imu(self, msg: Any, frame_id: str) -> Any:
        """``sensor_msgs/Imu`` from an ``ImuMsg``: orientation of ``frame_id`` (FLU) in ENU,
        rates and specific force in FLU (reads +9.81 m/s^2 up at rest). Covariances unknown (0)."""
        R_nb = rot_from_euler(*msg.rpy_rad)
        return build(self.store, "sensor_msgs/msg/Imu", header=self.header(msg.t_s, frame_id),
                     orientation=self.quaternion(rot_enu_flu(R_nb)),
                     angular_velocity=self.vector3(flu_from_frd(msg.rate_body_radps)),
                     linear_acceleration=self.vector3(flu_from_frd(msg.accel_body_mps2)))

    def fluid_pressure(self, msg: Any, frame_id: str, rho_kgpm3: float, gravity_mps2: float) -> Any:
        """``sensor_msgs/FluidPressure`` (absolute, Pa) of a ``DepthMsg``:
        ``101325 + rho g depth``; variance unknown (0)."""
        p = ATMOSPHERE_PA + rho_kgpm3 * gravity_mps2 * float(msg.depth_m)
        return build(self.store, "sensor_msgs/msg/FluidPressure", header=self.header(msg.t_s, frame_id),
                     fluid_pressure=p)

    def range_altimeter(self, msg: Any, frame_id: str, min_range_m: float, max_range_m: float) -> Any:
        """``sensor_msgs/Range`` of an ``AltimeterMsg`` (ULTRASOUND; +inf without a return, REP 117)."""
        r = float(msg.altitude_m) if msg.valid and math.isfinite(msg.altitude_m) else math.inf
        return build(self.store, "sensor_msgs/msg/Range", header=self.header(msg.t_s, frame_id),
                     radiation_type=0, field_of_view=0.0, min_range=float(min_range_m),
                     max_range=float(max_range_m), range=r)

    def dvl(self, msg: Any, frame_id: str, beam_dirs_frd: ArrayLike) -> Any:
        """``marine_acoustic_msgs/Dvl`` of a ``DvlMsg`` in ``frame_id`` (FRD axes: z down along
        the DVL's pointing direction, x forward). Velocity NaN without bottom lock;
        covariances -1 (unknown)."""
        v = np.asarray(msg.vel_body_mps, dtype=float)
        ranges = np.asarray(msg.beam_ranges_m, dtype=float).reshape(4)
        dirs = np.asarray(beam_dirs_frd, dtype=float).reshape(4, 3)
        T = self.store.types["marine_acoustic_msgs/msg/Dvl"]
        return build(self.store, "marine_acoustic_msgs/msg/Dvl", header=self.header(msg.t_s, frame_id),
                     velocity_mode=T.DVL_MODE_BOTTOM, dvl_type=T.DVL_TYPE_PISTON, velocity=self.vector3(v),
                     velocity_covar=np.full(9, -1.0), altitude=float(msg.altitude_m),
                     course_gnd=float(math.atan2(v[1], v[0])), speed_gnd=float(math.hypot(v[0], v[1])),
                     num_good_beams=int(np.isfinite(ranges).sum()), beam_ranges_valid=True,
                     beam_velocities_valid=False, beam_unit_vec=[self.vector3(d) for d in dirs],
                     range=ranges, range_covar=np.full(4, -1.0, dtype=np.float32),
                     beam_velocity_covar=np.full(4, -1.0, dtype=np.float32))

    def projected_sonar_image(self, frame: Any, frame_id: str, beam_azimuths_rad: ArrayLike,
                              bin_centres_m: ArrayLike, frequency_hz: float = 0.0, sound_speed_mps: float = 0.0,
                              tx_beamwidth_rad: float | None = None, rx_beamwidth_rad: float | None = None) -> Any:
        """``marine_acoustic_msgs/ProjectedSonarImage`` of an ``FlsFrame``'s polar image.

        ``frame.polar`` is (n_beams, n_bins) uint8; the message stores it one range bin after
        the other with the beam index fastest (``data[bin * n_beams + beam]``), the layout of
        the marine_acoustic_msgs drivers. Beam directions are unit vectors in ``frame_id``.

        ``ping_info``: ``frequency`` (Hz) and ``sound_speed`` (m/s, the speed the ranges were
        computed with), 0 where unknown; per beam (``n_beams`` entries each, empty where not
        given) ``tx_beamwidths`` the transmit fan's vertical -3 dB aperture and
        ``rx_beamwidths`` the receive beam's horizontal -3 dB width, rad.
        """
        polar = np.asarray(frame.polar, dtype=np.uint8)
        az = np.asarray(beam_azimuths_rad, dtype=float)
        if polar.shape != (az.size, np.size(bin_centres_m)):
            raise ValueError(f"polar image {polar.shape} does not match {az.size} beams x "
                             f"{np.size(bin_centres_m)} bins")
        beams, ranges = self._sonar_beams(az, bin_centres_m)
        # bin-major bytes: one contiguous uint8 buffer handed to the serializer as is
        # (cv2.transpose: ~4x faster than numpy's strided copy on uint8)
        data = cv2.transpose(np.ascontiguousarray(polar)).reshape(-1)
        T = self.store.types
        return T["marine_acoustic_msgs/msg/ProjectedSonarImage"](
            header=self.header(frame.t_s, frame_id),
            ping_info=build(self.store, "marine_acoustic_msgs/msg/PingInfo", frequency=float(frequency_hz),
                            sound_speed=float(sound_speed_mps),
                            tx_beamwidths=_per_beam(tx_beamwidth_rad, az.size),
                            rx_beamwidths=_per_beam(rx_beamwidth_rad, az.size)),
            beam_directions=beams, ranges=ranges,
            image=T["marine_acoustic_msgs/msg/SonarImageData"](
                is_bigendian=False, dtype=0, beam_count=int(az.size), data=data))

    def detections(self, result: Any, frame_id: str) -> Any:
        """``vision_msgs/Detection2DArray`` of a perception result: boxes in fan-image pixels,
        class and score, and each detection's reference point (range, azimuth, elevation 0)
        as the hypothesis pose in ``frame_id`` (the sonar message frame)."""
        s, T = self.store, self.store.types
        header = self.header(result.t_s, frame_id)
        out = []
        for i, d in enumerate(result.detections):
            x0, y0, x1, y1 = (float(c) for c in d.box_xyxy_px)
            p_msg = ray_directions_sonar(d.azimuth_rad, 0.0) * float(d.range_m) @ R_SONAR_SONARMSG
            hyp = T["vision_msgs/msg/ObjectHypothesisWithPose"](
                hypothesis=T["vision_msgs/msg/ObjectHypothesis"](class_id=str(d.class_name), score=float(d.score)),
                pose=build(s, "geometry_msgs/msg/PoseWithCovariance", pose=self.pose(p_msg, np.eye(3))))
            bbox = T["vision_msgs/msg/BoundingBox2D"](
                center=T["vision_msgs/msg/Pose2D"](position=T["vision_msgs/msg/Point2D"](
                    x=0.5 * (x0 + x1), y=0.5 * (y0 + y1)), theta=0.0),
                size_x=x1 - x0, size_y=y1 - y0)
            out.append(T["vision_msgs/msg/Detection2D"](header=header, results=[hyp], bbox=bbox, id=str(i)))
        return T["vision_msgs/msg/Detection2DArray"](header=header, detections=out)

    def world_model_markers(self, t_s: float, objects: Any, frame_id: str, target_class: str = "target") -> Any:
        """``visualization_msgs/MarkerArray``: DELETEALL, then one sphere per world-model
        object at its ENU position, sized to its 2-sigma extent (>= 0.1 m), orange for
        the target class, grey otherwise."""
        s, T = self.store, self.store.types
        Marker = T["visualization_msgs/msg/Marker"]
        header = self.header(t_s, frame_id)
        markers = [build(s, "visualization_msgs/msg/Marker", header=header, ns="world_model", action=Marker.DELETEALL)]
        for o in objects:
            sigma = np.sqrt(np.clip(np.diag(cov_enu_from_ned(o.cov_ned)), 0.0, None))
            is_target = getattr(o, "class_name", "") == target_class
            color = (1.0, 0.55, 0.1, 0.8) if is_target else (0.5, 0.5, 0.5, 0.6)
            markers.append(build(
                s, "visualization_msgs/msg/Marker", header=header, ns="world_model", id=int(o.id),
                type=Marker.SPHERE, action=Marker.ADD, pose=self.pose(enu_from_ned(o.pos_ned), np.eye(3)),
                scale=self.vector3(np.maximum(4.0 * sigma, 0.1)),
                color=T["std_msgs/msg/ColorRGBA"](r=color[0], g=color[1], b=color[2], a=color[3]),
                text=f"{o.id} {getattr(o, 'class_name', '')}"))
        return T["visualization_msgs/msg/MarkerArray"](markers=markers)


def sonar_msg_frame_in_flu(mount_pos_body_m: ArrayLike, mount_rpy_rad: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Translation (3,) in FLU, m, and rotation (3, 3) ProjectedSonarImage axes -> FLU body
    of a sonar mounted at ``mount_pos_body_m`` (FRD, m) with ``mount_rpy_rad`` (roll, tilt
    down > 0, yaw)."""
    R = R_FLU_FRD @ sonar_to_body_rotation(mount_rpy_rad) @ R_SONAR_SONARMSG
    return flu_from_frd(mount_pos_body_m), R
