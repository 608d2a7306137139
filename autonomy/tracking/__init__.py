"""Onboard tracking of a moving target (a diver) by fusing USBL fixes and imaging-sonar
detections (paper 004, docs/references.md [P004])."""

import lazy_loader

# names resolved on first use, so importing one submodule (a config, say) loads no other
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "config": ["TrackingConfig"],
    "kinematics": ["TargetKinematics"],
    "roi": ["PolarRoi", "polar_roi"],
    "tracker": ["TargetTracker"],
})
