"""Target geolocalisation: FLS detections -> NED positions with covariance (paper 000 IV)."""

import lazy_loader

# names resolved on first use, so importing one submodule (a config, say) loads no other
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "field_of_view": ["fls_visibility"],
    "geolocate": ["LocalizedDetection", "SHARED_ERRORS", "covariance_root", "localize", "sonar_point_ned"],
    "sonar_projection": ["flat_seabed_elevation", "planar_point_sonar", "sonar_to_body_rotation", "spherical_to_sonar"],
})
