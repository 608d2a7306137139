"""The world model on the surface: PMHA on the detections an acoustic link delivers.

Paper 000 section VII (docs/references.md [P000]) runs the data-association world model on
the buoy, from the detections the AUV sends over the acoustic modem. Each report carries its
frame's absolute time and the detection in latitude / longitude / depth; the reports of one
sonar frame (one PMHA scan) leave the AUV together and arrive one packet after another,
seconds after the frame, some lost. :class:`SurfaceWorldModel` therefore

- converts each report into the mission frame (:meth:`DetectionReport.to_localized`), with
  the measurement time from the message, not the arrival time;
- groups reports by frame time and hands a scan to the PMHA once it is complete: a report
  of a later frame has arrived (the link delivers in sending order, so nothing of the earlier
  frame is still to come) or ``hold_s`` has passed since the frame;
- processes scans in time order; a report older than the last processed scan (it cannot be
  inserted into the hypothesis tree's past) is counted in ``n_too_late`` and dropped.

The surface does not see the sonar's field of view at each frame, nor the frames without
detections: every anchor gets the PMHA's visibility floor (detected with probability
``p_detect * visibility_floor``), so an object is never penalised for a miss the surface
cannot know about, where the onboard model also uses the frames' fields of view.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from autonomy.comms.messages import DetectionReport
from autonomy.geodesy import GeodeticOrigin
from autonomy.localization.geolocate import LocalizedDetection
from autonomy.world_model.config import WorldModelConfig
from autonomy.world_model.pmha import PMHA, WorldObject


def unseen(points_ned: np.ndarray) -> np.ndarray:
    """Visibility for a PMHA that does not know the sonar's field of view: 0 for every point
    (the PMHA then uses its ``visibility_floor``)."""
    return np.zeros(len(points_ned))


class SurfaceWorldModel:
    """PMHA fed with delivered detection reports, in measurement-time order.

    Args:
        cfg: the world model's config (the same as the onboard one).
        region_ned: ((3,) min, (3,) max) surveyed volume, NED m (as the onboard PMHA's).
        origin: the mission frame's geodetic origin.
        epoch_unix_s: UNIX time of mission time 0, s.
        class_names: the class table of the reports' class ids.
        hold_s: a scan is processed at the latest this long after its frame time, s.

    Attributes:
        pmha: the world model.
        n_reports, n_scans, n_too_late: reports received, scans processed, reports dropped
            for arriving after a later scan was processed.
    """

    def __init__(self, cfg: WorldModelConfig, region_ned: tuple[ArrayLike, ArrayLike], origin: GeodeticOrigin,
                 epoch_unix_s: float, class_names: Sequence[str], *, hold_s: float = 10.0) -> None:
        if not hold_s >= 0.0:
            raise ValueError(f"hold_s must be >= 0, got {hold_s}")
        self.pmha = PMHA(cfg, region_ned=region_ned)
        self.origin, self.epoch_unix_s = origin, float(epoch_unix_s)
        self.class_names = tuple(class_names)
        self.hold_s = float(hold_s)
        self._pending: dict[float, list[LocalizedDetection]] = {}
        self.n_reports = self.n_scans = self.n_too_late = 0

    def receive(self, report: DetectionReport) -> None:
        """Take one delivered report (buffered until its scan is complete)."""
        self.n_reports += 1
        det = report.to_localized(self.origin, self.epoch_unix_s, self.class_names)
        t = round(det.t_s, 3)  # the message's millisecond time stamp names the frame
        if t <= self.pmha.t_s:
            self.n_too_late += 1
            return
        self._pending.setdefault(t, []).append(det)

    def flush(self, t_now_s: float, *, final: bool = False) -> int:
        """Process, in time order, the complete scans at mission time ``t_now_s``: those
        older than the newest frame received, those older than ``hold_s``, and with
        ``final`` every pending one. Returns the number of scans processed."""
        if not self._pending:
            return 0
        newest = max(self._pending)
        done = sorted(t for t in self._pending if final or t < newest or t <= t_now_s - self.hold_s)
        for t in done:
            self.pmha.update(t, self._pending.pop(t), unseen)
            self.n_scans += 1
        return len(done)

    def world_model(self) -> list[WorldObject]:
        return self.pmha.world_model()

    def to_json(self) -> dict:
        """The PMHA's JSON (:meth:`PMHA.to_json`) with the link counters."""
        out = self.pmha.to_json()
        out.update(reports_received=self.n_reports, scans=self.n_scans, reports_too_late=self.n_too_late)
        return out
