"""Target geolocalisation: FLS detections -> NED positions with covariance (paper 000 IV)."""

from autonomy.localization.field_of_view import fls_visibility
from autonomy.localization.geolocate import LocalizedDetection, localize, sonar_point_ned
from autonomy.localization.sonar_projection import (
    flat_seabed_elevation,
    planar_point_sonar,
    sonar_to_body_rotation,
    spherical_to_sonar,
)

__all__ = [
    "LocalizedDetection",
    "flat_seabed_elevation",
    "fls_visibility",
    "localize",
    "planar_point_sonar",
    "sonar_point_ned",
    "sonar_to_body_rotation",
    "spherical_to_sonar",
]
