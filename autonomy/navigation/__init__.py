"""Onboard navigation: AHRS + DVL dead reckoning and an EKF fusing depth, GPS and USBL."""

from autonomy.navigation.ekf import NavigationFilter
from autonomy.navigation.noise_model import NavNoiseModel

__all__ = ["NavNoiseModel", "NavigationFilter"]
