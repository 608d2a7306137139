"""Onboard navigation: AHRS + DVL dead reckoning and an EKF fusing depth, GPS and USBL."""

import lazy_loader

# names resolved on first use, so importing one submodule (a config, say) loads no other
__getattr__, __dir__, __all__ = lazy_loader.attach(__name__, submod_attrs={
    "ekf": ["NavigationFilter"],
    "noise_model": ["NavNoiseModel"],
})
