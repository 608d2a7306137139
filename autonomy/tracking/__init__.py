"""Onboard tracking of a moving target (a diver) by fusing USBL fixes and imaging-sonar
detections (paper 004, docs/references.md [P004])."""

from autonomy.tracking.config import TrackingConfig
from autonomy.tracking.kinematics import TargetKinematics
from autonomy.tracking.roi import PolarRoi, polar_roi
from autonomy.tracking.tracker import TargetTracker

__all__ = ["PolarRoi", "TargetKinematics", "TargetTracker", "TrackingConfig", "polar_roi"]
