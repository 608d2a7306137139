"""From binned echo energy to the displayed echo lines: one chain for every sonar.

Per range bin: two-way spreading and absorption (:mod:`sim.sensors.sonar.propagation`); across
lines: the azimuth beam pattern (:mod:`sim.sensors.sonar.beam_pattern`); then speckle and
receiver noise (:mod:`sim.sensors.sonar.speckle`), time-varied gain, gain and the dB display
mapping (:mod:`sim.sensors.sonar.display`). A forward-looking sonar passes its fan of lines, a
single-beam scanning sonar one line per ping, a side-scan sonar one line per side.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from sim.sensors.sonar.beam_pattern import apply_azimuth_pattern
from sim.sensors.sonar.display import to_uint8_db
from sim.sensors.sonar.image_formation import (FormationModel, lognormal_texture, rician_speckle, speckle_field,
                                               to_uint8_gamma)
from sim.sensors.sonar.propagation import transmission_gain, tvg_gain
from sim.sensors.sonar.speckle import SpeckleKind, add_speckle_and_noise, standard_exponential_f32
from sim.sensors.sonar.speckle_display import CounterSpeckleDisplay

FloatArray = NDArray[np.float64]


class EchoChain:
    """Propagation, beam pattern, noise and display for echo lines on one range axis.

    Args:
        bin_centres_m: (n_bins,) slant range of each bin centre (m).
        absorption_db_per_m: one-way absorption of the water at the sonar's frequency.
        tvg_db_per_decade: spreading part ``N`` of the time-varied gain.
        tvg_absorption_db_per_m: absorption the time-varied gain compensates (0: none).
        noise_floor_db: receiver noise power (dB re unit echo power).
        speckle: ``"none"``, ``"rayleigh"`` or ``"k"`` (:func:`add_speckle_and_noise`).
        k_shape: shape of the K-distribution texture.
        gain_db, dynamic_range_db: display gain and the dB span mapped onto 0..255.
        azimuth_kernel: (2K + 1,) pattern across lines (:func:`sim.sensors.sonar.beam_pattern.azimuth_kernel`);
            default a single tap (lines do not overlap).
        formation: correlated speckle, seabed texture, volume reverberation and the power-law
            display (:class:`sim.sensors.sonar.image_formation.FormationModel`); None: none of
            them (independent speckle per bin, dB display).
        counter_speckle: draw Rayleigh speckle and noise with the counter-based generator and
            display them in the same pass (:mod:`sim.sensors.sonar.speckle_display`) where
            :meth:`realise_display` can (``speckle`` rayleigh or k, no correlated speckle,
            texture or Rice objects, the dB display); False: every pixel from the generator's
            stream (:meth:`realise`, then :meth:`display`).

    Raises:
        ValueError: if ``bin_centres_m`` is empty or ``dynamic_range_db`` is not positive.
    """

    def __init__(self, bin_centres_m: ArrayLike, absorption_db_per_m: float, tvg_db_per_decade: float,
                 tvg_absorption_db_per_m: float, noise_floor_db: float, speckle: SpeckleKind, k_shape: float,
                 gain_db: float, dynamic_range_db: float,
                 azimuth_kernel: NDArray[np.float32] | None = None, *,
                 formation: FormationModel | None = None, counter_speckle: bool = False) -> None:
        bins_m = np.asarray(bin_centres_m, dtype=float).reshape(-1)
        if bins_m.size == 0 or not dynamic_range_db > 0.0:
            raise ValueError("need at least one range bin and dynamic_range_db > 0")
        # r^-2 undoes the r_a r_b weighting of segment energies (sim.sensors.sonar.echo_lines)
        self.bin_gain = transmission_gain(bins_m, absorption_db_per_m) / np.maximum(bins_m, 1e-3) ** 2
        self._bin_gain32 = self.bin_gain.astype(np.float32)
        self.tvg = tvg_gain(bins_m, tvg_db_per_decade, tvg_absorption_db_per_m).astype(np.float32)
        self.noise_power = 10.0 ** (0.1 * noise_floor_db)
        self.speckle: SpeckleKind = speckle
        self.k_shape = float(k_shape)
        self.gain_db = float(gain_db)
        self.dynamic_range_db = float(dynamic_range_db)
        self.azimuth_kernel = np.ones(1, dtype=np.float32) if azimuth_kernel is None else azimuth_kernel
        self.formation = formation
        rk = None if formation is None else formation.range_kernel.astype(np.float64)
        self._range_psf = (None if rk is None or rk.size < 2
                           else ((rk ** 2) / np.sum(rk ** 2)).astype(np.float32).reshape(1, -1))
        self._reverb = (None if formation is None or not np.any(formation.reverberation > 0)
                        else formation.reverberation.astype(np.float32))
        f = formation
        plain = f is None or not (f.correlated or f.textured or f.object_rice_k > 0.0 or f.display_gamma is not None)
        self.counter = (CounterSpeckleDisplay(self.tvg, self.gain_db, self.dynamic_range_db, self.noise_power,
                                              self.k_shape if speckle == "k" else None)
                        if counter_speckle and speckle in ("rayleigh", "k") and plain else None)

    @property
    def needs_clutter(self) -> bool:
        """Whether :meth:`realise` reads a clutter mask (the K or the seabed texture)."""
        f = self.formation
        return self.speckle == "k" or (f is not None and (f.textured or f.object_rice_k > 0.0))

    def mean_intensity(self, energy_lines: NDArray[np.float32]) -> NDArray[np.float32]:
        """Noise-free received power (n_lines, n_bins) of binned echo energy (n_lines, n_bins).

        Applies the per-bin spreading and absorption in place (``energy_lines`` is consumed),
        then the azimuth pattern across lines and, with a formation model's pulse longer than
        a bin, the range point-spread function (the pulse's power envelope, unit sum).
        """
        img = np.multiply(energy_lines, self._bin_gain32[None, :], out=energy_lines)
        img = apply_azimuth_pattern(img, self.azimuth_kernel)
        if self._range_psf is not None:
            # causal: an echo at range r is received from r to r + pulse length (filter2D
            # correlates: the kernel reversed, anchored on its last tap)
            k = self._range_psf
            img = cv2.filter2D(img, -1, k[:, ::-1].copy(), anchor=(k.shape[1] - 1, 0), borderType=cv2.BORDER_CONSTANT)
        if self._reverb is not None:
            img = np.add(img, self._reverb[None, :], out=img)
        return img

    def realise(self, mean: NDArray[np.float32], rng: np.random.Generator, *, noise: bool = True,
                clutter: NDArray[np.bool_] | None = None) -> NDArray[np.float32]:
        """Received intensity (n_lines, n_bins): speckle and receiver noise drawn from ``rng``,
        the K texture only where ``clutter``; ``noise=False`` gives ``mean + noise power``."""
        f = self.formation
        if noise and f is not None and (f.correlated or f.textured or f.object_rice_k > 0.0):
            return self._realise_formed(mean, rng, clutter)
        if noise:
            return add_speckle_and_noise(mean, rng, self.speckle, self.noise_power, k_shape=self.k_shape,
                                         clutter=clutter)
        return mean + np.float32(self.noise_power)

    def realise_display(self, mean: NDArray[np.float32], rng: np.random.Generator, *, noise: bool = True,
                        clutter: NDArray[np.bool_] | None = None) -> tuple[NDArray[np.float32], NDArray[np.uint8]]:
        """:meth:`realise` and :meth:`display` of ``mean`` (n_lines, n_bins): the received
        intensity and its 8-bit lines. With the counter-based speckle (``counter_speckle`` and a
        chain it applies to) and ``noise``, one compiled pass and one draw from ``rng``
        (:class:`sim.sensors.sonar.speckle_display.CounterSpeckleDisplay`); otherwise the two
        steps."""
        if noise and self.counter is not None:
            return self.counter.realise_display(mean, rng, clutter)
        intensity = self.realise(mean, rng, noise=noise, clutter=clutter)
        return intensity, self.display(intensity)

    def _realise_formed(self, mean: NDArray[np.float32], rng: np.random.Generator,
                        clutter: NDArray[np.bool_] | None) -> NDArray[np.float32]:
        """:meth:`realise` with the formation model: texture on the clutter (then the K texture
        if asked), correlated speckle, independent receiver noise."""
        f = self.formation
        m = mean
        if f.textured:
            tex = lognormal_texture(mean.shape, rng, f.texture_sigma, f.texture_corr_bins, f.texture_corr_lines)
            if clutter is not None:
                np.copyto(tex, np.float32(1.0), where=~clutter)
            m = np.multiply(m, tex, out=tex)
        if self.speckle == "k":
            tex = rng.standard_gamma(self.k_shape, mean.shape, dtype=np.float32)
            tex *= np.float32(1.0 / self.k_shape)
            if clutter is not None:
                np.copyto(tex, np.float32(1.0), where=~clutter)
            m = np.multiply(m, tex, out=tex)
        if self.speckle == "none":
            out = np.array(m, dtype=np.float32, copy=True)
        elif f.correlated or f.object_rice_k > 0.0:
            re, im = speckle_field(mean.shape, rng, f.range_kernel, f.beam_kernel)
            if f.object_rice_k > 0.0 and clutter is not None:
                out = np.where(clutter, re * re + im * im, rician_speckle(re, im, f.object_rice_k))
            else:
                out = re * re + im * im
            out *= m
        else:
            return add_speckle_and_noise(np.ascontiguousarray(m, dtype=np.float32), rng, "rayleigh",
                                         self.noise_power)
        if self.noise_power > 0.0:
            out += np.float32(self.noise_power) * standard_exponential_f32(rng, mean.shape)
        return out

    def display(self, intensity: NDArray[np.float32]) -> NDArray[np.uint8]:
        """8-bit echo lines: time-varied gain, gain and the display mapping (dB, or the
        formation model's power law)."""
        if self.formation is not None and self.formation.display_gamma is not None:
            return to_uint8_gamma(intensity, self.tvg, self.gain_db, self.formation.display_gamma,
                                  self.formation.display_soft_limit)
        return to_uint8_db(intensity, self.tvg, self.gain_db, self.dynamic_range_db)
