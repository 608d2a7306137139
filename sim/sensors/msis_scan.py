"""Scan images of a mechanically scanned sonar: the pings of a sweep as a polar image (one row
per gradian of head angle) and a Cartesian image centred on the head, each with per-sample
ground-truth labels (:mod:`sim.sensors.msis`), for users who train learned methods.

Like the device's own display, a ping fills the rows of its head angle up to the next step
(``step_grad`` rows) and the images are drawn in the head frame *as the pings arrive*: the
vehicle's motion during a sweep distorts them as it does at sea (the per-ping poses are kept
in :attr:`ScanImage.poses` for motion compensation).
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from autonomy.msis.ping360 import GRAD_PER_TURN
from sim.sensors.msis import NO_ECHO_ID, MsisRender

FloatArray = NDArray[np.float64]


class ScanImage:
    """Accumulates pings into polar and Cartesian scan images.

    Args:
        n_samples: samples per ping.
        sample_spacing_m: range per sample, m.
        size_px: side of the square Cartesian image; the head at its centre, the beam at
            angle 0 pointing up, angles clockwise; ``2 n_samples sample_spacing / size_px``
            metres per pixel.

    Attributes:
        polar: (400, n_samples) uint8, row = head angle in gradians.
        polar_labels: (400, n_samples) int16 truth labels (``NO_ECHO_ID`` where no ping yet).
        poses: per ping ``(t_s, angle_grad, head pos_ned (3,), R_ns (3, 3))``.
    """

    def __init__(self, n_samples: int, sample_spacing_m: float, size_px: int = 400) -> None:
        self.n_samples = int(n_samples)
        self.sample_spacing_m = float(sample_spacing_m)
        self.size_px = int(size_px)
        self.m_per_px = 2.0 * self.n_samples * self.sample_spacing_m / self.size_px
        self.polar = np.zeros((GRAD_PER_TURN, self.n_samples), dtype=np.uint8)
        self.polar_labels = np.full((GRAD_PER_TURN, self.n_samples), NO_ECHO_ID, dtype=np.int16)
        self.poses: list[tuple[float, float, FloatArray, FloatArray]] = []
        c = 0.5 * (self.size_px - 1)
        v, u = np.mgrid[0:self.size_px, 0:self.size_px].astype(np.float64)
        fwd = (c - v) * self.m_per_px
        stbd = (u - c) * self.m_per_px
        r = np.hypot(fwd, stbd)
        ang = np.mod(np.arctan2(stbd, fwd) * (GRAD_PER_TURN / (2.0 * np.pi)), GRAD_PER_TURN)
        inside = r < self.n_samples * self.sample_spacing_m
        # a sample k covers [k, k + 1) spacings; row a covers [a, a + 1) gradians
        self._map_bin = np.where(inside, r / self.sample_spacing_m, -10.0).astype(np.float32)
        self._map_row = np.where(inside, np.floor(ang), -10.0).astype(np.float32)

    @classmethod
    def for_sensor(cls, sensor, size_px: int | None = None) -> "ScanImage":
        """An empty scan image for a :class:`sim.sensors.msis.MsisSensor`."""
        return cls(sensor.n_samples, sensor.sample_spacing_m, size_px or sensor.cfg.scan_image_px)

    def add(self, render: MsisRender) -> None:
        """Write one ping (and its labels) into the rows of its head angle."""
        p = render.ping
        rows = (int(round(p.angle_grad)) + np.arange(max(int(p.step_grad), 1))) % GRAD_PER_TURN
        self.polar[rows] = p.intensity
        self.polar_labels[rows] = render.truth.labels
        self.poses.append((p.t_s, p.angle_grad, render.truth.pos_ned, render.truth.R_ns))

    def cartesian(self) -> NDArray[np.uint8]:
        """(size_px, size_px) uint8 image in the head frame (forward up, starboard right)."""
        return cv2.remap(self.polar, self._map_bin - 0.5, self._map_row, cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0)

    def cartesian_labels(self) -> NDArray[np.int16]:
        """(size_px, size_px) int16 labels of :meth:`cartesian`'s pixels (nearest sample)."""
        return cv2.remap(self.polar_labels, np.floor(self._map_bin), self._map_row, cv2.INTER_NEAREST,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=int(NO_ECHO_ID))
