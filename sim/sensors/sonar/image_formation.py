"""Image formation beyond independent speckle: correlated speckle, seabed texture, volume
reverberation and a power-law display (pure numpy + OpenCV).

What each models, and its source (keys of ``docs/references.md``):

* **Correlated speckle** ([Goodman2007]). The echo of one range sample is the
  sum of the scatterers inside one resolution cell: a pulse length along range, a beam width
  across. Samples closer than that share scatterers, so their complex amplitudes are
  correlated. The complex field is circular Gaussian white noise filtered along range by
  the pulse envelope (a rectangle ``pulse_length_m`` long; the bin size only samples it) and
  across beams by the two-way amplitude pattern of the beams (:func:`beam_amplitude_kernel`),
  both normalised to unit energy so the intensity stays unit-mean exponential at every sample.
* **Coherent object echoes** ([Goodman2007], Rice's law). A smooth object's echo is
  dominated by a few specular facets: a coherent part plus diffuse speckle, so its
  intensity is Rician (Rice factor ``object_rice_k``) and fluctuates less than the floor's.
* **Seabed texture** ([Abraham2002]). The number of scatterers per cell and
  their strength vary over the bottom: the mean is modulated by a unit-mean log-normal
  texture whose log is a Gaussian field correlated over ``texture_corr_m``. The compound of
  texture and speckle is heavy-tailed (K-like) where the texture varies within the image.
* **Volume reverberation** ([Urick1983] ch. 8). Scatterers in the water column return
  ``s_v V r^-4`` from a cell of volume ``V ~ r^2`` (beam solid angle times pulse length):
  ``r^-2`` with two-way absorption, a level that 20 log r TVG shows flat, filling shadows
  where electronic noise alone is far below the echoes.
* **Object echo tails** ([Urick1983] ch. 8 on multipath; [Williams2010] on the elastic
  ringing of shells). A debris object's echo goes on after its first return: sound bounces
  between the object and the floor, and a water-filled shell (a can, a bottle) rings. Each
  beam's object echo is followed by an exponentially decaying tail along range, of length
  ``object_tail_m`` and total energy ``object_tail_ratio`` times the direct echo; it fills
  the object's acoustic shadow and stretches the object along range, as in real frames.
* **Specular objects** ([Urick1983] ch. 9; [Blondel2009] on specular returns from man-made objects). Smooth
  plastic and metal scatter mostly where the surface faces the sonar: an object's strength is
  ``(1 - s) cos^m + s cos^n`` of the incidence, ``m`` the sonar's diffuse exponent, ``n``
  ``object_specular_exponent`` and ``s`` ``object_specular_share``, so a lying cylinder
  returns a bright line along its ridge rather than a filled outline.
* **Back-wall echoes** ([Williams2010], [Urick1983] ch. 9 on echoes from shells). A thin
  shell of plastic or metal filled with water passes most of the sound, so a bottle or a can
  returns from its far wall as well as its near one, and sound ringing between the walls
  returns again one crossing later. Each ray that hits an object is followed through the
  mesh to where it leaves it; its echo is repeated there (and ``k`` crossings later) with
  ``object_back_wall_ratio ** k`` of the energy, so a lying bottle shows two or three
  parallel streaks along range, as real frames do. Labelled with the object (part of its
  image).
* **Power-law display** (an adjustable gamma on the amplitude, as sonar viewers offer
  beside the log display; the exponent a set calls for is estimated from its grey
  histogram, ``docs/studies/realism.md``). Grey
  ``255 (I g / I_0)^(gamma / 2)``: amplitude to the power ``gamma``; ``gamma -> 0``
  approaches a log display. Optionally through a soft limiter (``tanh``), as a receiver
  saturates gradually rather than clipping.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from sim.sensors.sonar.beam_pattern import SINC_3DB
from sim.sensors.sonar.ray_fan import row_dot
from sim.sensors.sonar.speckle import complement_uniform_f32


def beam_amplitude_kernel(spacing_rad: float, beamwidth_rad: float, extent_beamwidths: float) -> NDArray[np.float32]:
    """Two-way amplitude pattern ``sinc^2(SINC_3DB theta / beamwidth)`` of a uniform line
    aperture ([Urick1983] ch. 3) sampled every ``spacing_rad`` out to ``+-extent_beamwidths``,
    normalised to unit energy (sum of squares 1): (2K + 1,) float32."""
    half = max(int(np.ceil(extent_beamwidths * beamwidth_rad / spacing_rad)), 0)
    k = np.sinc(SINC_3DB * np.arange(-half, half + 1) * spacing_rad / beamwidth_rad) ** 2
    return (k / np.sqrt(np.sum(k ** 2))).astype(np.float32)


def pulse_kernel(pulse_length_bins: float) -> NDArray[np.float32]:
    """A rectangular pulse envelope ``pulse_length_bins`` bins long, sampled at the bins (the
    last tap fractional), normalised to unit energy: (ceil(L),) float32; one tap for L <= 1."""
    n = max(int(np.ceil(pulse_length_bins - 1e-9)), 1)
    k = np.ones(n)
    if n > 1:
        k[-1] = pulse_length_bins - (n - 1)
    return (k / np.sqrt(np.sum(k ** 2))).astype(np.float32)


@dataclass(frozen=True)
class FormationModel:
    """The parts of the image formation :class:`EchoChain` applies when set.

    Attributes:
        range_kernel: (n,) unit-energy pulse envelope across range bins (:func:`pulse_kernel`).
        beam_kernel: (m,) unit-energy amplitude pattern across lines (:func:`beam_amplitude_kernel`).
        texture_sigma: standard deviation of the texture's log (0: no texture).
        texture_corr_bins, texture_corr_lines: correlation lengths (Gaussian sigma) of the
            texture's log along range (bins) and across lines.
        reverberation: (n_bins,) volume reverberation power per bin before TVG (zeros: none).
        display_gamma: amplitude exponent of the display (None: the dB display).
        display_soft_limit: the power-law display limits softly (``tanh``).
        object_rice_k: Rice factor of object echoes (coherent over diffuse power; 0: Rayleigh).
        tail_decay: per-bin decay factor of the object echo tail (0: no tail).
        tail_ratio: the tail's energy over the direct object echo.
        specular_share, specular_exponent: an object's specular lobe (share, cos exponent).
        back_wall_ratio: energy of each back-wall echo over the previous one (0: none).
        back_wall_repeats: back-wall echoes after the near wall's.
    """

    range_kernel: NDArray[np.float32]
    beam_kernel: NDArray[np.float32]
    texture_sigma: float
    texture_corr_bins: float
    texture_corr_lines: float
    reverberation: NDArray[np.float32]
    display_gamma: float | None
    display_soft_limit: bool = False
    tail_decay: float = 0.0
    tail_ratio: float = 0.0
    object_rice_k: float = 0.0
    back_wall_ratio: float = 0.0
    back_wall_repeats: int = 1
    specular_share: float = 0.0
    specular_exponent: float = 20.0

    @property
    def has_tail(self) -> bool:
        return self.tail_decay > 0.0 and self.tail_ratio > 0.0

    @property
    def correlated(self) -> bool:
        return self.range_kernel.size > 1 or self.beam_kernel.size > 1

    @property
    def textured(self) -> bool:
        return self.texture_sigma > 0.0


def standard_normal_pair_f32(rng: np.random.Generator, shape: tuple[int, ...]
                             ) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """Two independent standard-normal float32 arrays of ``shape`` by the Box-Muller transform
    of two uniform draws (:func:`sim.sensors.sonar.speckle.complement_uniform_f32`, in (0, 1]):
    ``sqrt(-2 ln u1) (cos, sin)(2 pi u2)``, with OpenCV's SIMD log, sqrt and polar-to-Cartesian
    passes; about three times faster than two ``rng.standard_normal`` calls."""
    u1 = complement_uniform_f32(rng, shape)
    u2 = complement_uniform_f32(rng, shape)
    mag = cv2.log(u1, dst=u1)
    mag *= np.float32(-2.0)
    mag = cv2.sqrt(mag, dst=mag)
    u2 *= np.float32(2.0 * np.pi)
    x, y = cv2.polarToCart(mag.reshape(-1, 1), u2.reshape(-1, 1))
    return x.reshape(shape), y.reshape(shape)


def speckle_field(shape: tuple[int, int], rng: np.random.Generator, range_kernel: NDArray[np.float32],
                  beam_kernel: NDArray[np.float32]) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """Real and imaginary parts (each (n_lines, n_bins), variance 1/2) of a circular complex
    Gaussian field correlated along range by ``range_kernel`` and across lines by
    ``beam_kernel``: white noise (:func:`standard_normal_pair_f32`) filtered by the separable
    unit-energy kernels."""
    kx, ky = range_kernel.reshape(-1, 1), beam_kernel.reshape(-1, 1)
    scale = np.float32(np.sqrt(0.5))
    parts = []
    for w in standard_normal_pair_f32(rng, shape):
        if kx.size > 1 or ky.size > 1:
            w = cv2.sepFilter2D(w, -1, kx, ky, borderType=cv2.BORDER_REFLECT)
        w *= scale
        parts.append(w)
    return parts[0], parts[1]


def correlated_speckle(shape: tuple[int, int], rng: np.random.Generator, range_kernel: NDArray[np.float32],
                       beam_kernel: NDArray[np.float32]) -> NDArray[np.float32]:
    """Unit-mean exponential intensities (n_lines, n_bins), correlated along range by
    ``range_kernel`` and across lines by ``beam_kernel``: ``|z|^2`` of :func:`speckle_field`."""
    re, im = speckle_field(shape, rng, range_kernel, beam_kernel)
    out = cv2.multiply(re, re)
    out += cv2.multiply(im, im)
    return out


def rician_speckle(re: NDArray[np.float32], im: NDArray[np.float32], rice_k: float) -> NDArray[np.float32]:
    """Unit-mean intensities ``|c + s z|^2`` of a coherent part ``c^2 = K / (1 + K)`` plus a
    diffuse part ``s^2 = 1 / (1 + K)`` (Rice's law, [Goodman2007]: a dominant specular
    reflector among weaker scatterers); ``K = 0`` is fully developed (exponential) speckle."""
    c = np.float32(np.sqrt(rice_k / (1.0 + rice_k)))
    sd = np.float32(np.sqrt(1.0 / (1.0 + rice_k)))
    a = re * sd + c
    b = im * sd
    return a * a + b * b


def lognormal_texture(shape: tuple[int, int], rng: np.random.Generator, sigma: float, corr_bins: float,
                      corr_lines: float) -> NDArray[np.float32]:
    """Unit-mean log-normal texture (n_lines, n_bins): ``exp(sigma z - sigma^2 / 2)`` with ``z`` a
    unit-variance Gaussian field, white noise smoothed by Gaussians of ``corr_bins`` and
    ``corr_lines`` (sigma, samples) and rescaled to unit variance."""
    z = standard_normal_pair_f32(rng, shape)[0]
    if corr_bins > 0.0 or corr_lines > 0.0:
        kx = _gauss(corr_bins)
        ky = _gauss(corr_lines)
        z = cv2.sepFilter2D(z, -1, kx.reshape(-1, 1), ky.reshape(-1, 1), borderType=cv2.BORDER_REFLECT)
        z *= np.float32(1.0 / np.sqrt(np.sum(kx ** 2) * np.sum(ky ** 2)))
    z *= np.float32(sigma)
    z -= np.float32(0.5 * sigma * sigma)
    return cv2.exp(z)


def _gauss(sigma: float) -> NDArray[np.float32]:
    if sigma <= 0.0:
        return np.ones(1, dtype=np.float32)
    half = int(np.ceil(3.0 * sigma))
    x = np.arange(-half, half + 1, dtype=np.float64)
    k = np.exp(-0.5 * (x / sigma) ** 2)
    return (k / k.sum()).astype(np.float32)


def specular_objects(strength: NDArray[np.float64], rays, diffuse_exponent: float, share: float,
                     exponent: float) -> NDArray[np.float64]:
    """``strength`` (N,) of :func:`sim.sensors.sonar.echo_lines.ray_strength` with the rays on
    objects (``rays.obj >= 0``) re-weighted from ``cos^m`` to ``(1 - share) cos^m + share
    cos^exponent`` of their incidence (``m = diffuse_exponent``); a new array."""
    out = np.array(strength, dtype=np.float64, copy=True)
    on = np.flatnonzero(rays.obj >= 0)
    if on.size == 0:
        return out
    cos = np.abs(row_dot(rays.dirs[on], rays.normal[on]))
    diffuse = cos ** diffuse_exponent
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(diffuse > 0.0, ((1.0 - share) * diffuse + share * cos ** exponent) / diffuse, 0.0)
    out[on] *= factor
    return out


def object_tail(object_lines: NDArray[np.float32], decay: float, ratio: float) -> NDArray[np.float32]:
    """The echo tails of (n_lines, n_bins) object echo energy: each bin's energy followed, in
    the later bins of its line, by ``ratio (1 - decay) decay^(k - 1)`` of it at ``k`` bins
    (k >= 1; total ``ratio``). A first-order recursive filter along range (scipy's ``lfilter``)."""
    from scipy.signal import lfilter

    y = lfilter([0.0, ratio * (1.0 - decay)], [1.0, -decay], object_lines, axis=1)
    return y.astype(np.float32)


def to_uint8_gamma(intensity: NDArray[np.float32], gain_per_bin: NDArray[np.float32], gain_db: float,
                   gamma: float, soft_limit: bool = False) -> NDArray[np.uint8]:
    """Power-law display of (n_lines, n_bins) linear intensities: ``y = (I g 10^(gain_db/10))^(gamma/2)``
    shown as ``255 y`` (or ``255 tanh(y)`` with ``soft_limit``: a receiver that limits softly,
    so the brightest echoes approach white without piling up there), rounded and saturated to
    0..255 (0 dB after the gain shows as 255, or 194 with ``soft_limit``)."""
    x = np.ascontiguousarray(np.atleast_2d(intensity), dtype=np.float32) * (
        gain_per_bin.astype(np.float32)[None, :] * np.float32(10.0 ** (0.1 * gain_db)))
    np.maximum(x, np.float32(1e-30), out=x)
    y = cv2.pow(x, 0.5 * gamma)
    if soft_limit:
        y = np.tanh(y, out=y)
    return cv2.convertScaleAbs(y, alpha=255.0)


def formation_model(cfg, bin_centres_m: NDArray[np.float64], range_resolution_m: float, line_spacing_rad: float,
                    beamwidth_rad: float, absorption_db_per_m: float, extent_beamwidths: float
                    ) -> FormationModel | None:
    """The :class:`FormationModel` of a :class:`scenarios.config.sonar_formation.SonarFormationConfig`
    on one range axis (``bin_centres_m``, m, bins ``range_resolution_m`` apart) and line fan
    (``line_spacing_rad`` apart, beams ``beamwidth_rad`` wide, one-way -3 dB); None when every
    field is at its default. The texture's correlation across lines is taken at the window's
    middle range."""
    if cfg.is_default:
        return None
    bins = np.asarray(bin_centres_m, dtype=float)
    rk = pulse_kernel(cfg.pulse_length_m / range_resolution_m) if cfg.pulse_length_m else np.ones(1, np.float32)
    bk = (beam_amplitude_kernel(line_spacing_rad, beamwidth_rad, extent_beamwidths)
          if cfg.beam_correlated_speckle else np.ones(1, np.float32))
    if cfg.reverberation_db is not None:
        r = np.maximum(bins, 1e-3)
        reverb = 10.0 ** (0.1 * cfg.reverberation_db) * r ** -2 * 10.0 ** (-0.2 * absorption_db_per_m * r)
    else:
        reverb = np.zeros(bins.size)
    mid_m = float(np.median(bins)) if bins.size else 1.0
    return FormationModel(
        range_kernel=rk, beam_kernel=bk, texture_sigma=float(cfg.texture_sigma),
        texture_corr_bins=float(cfg.texture_corr_m / range_resolution_m),
        texture_corr_lines=float(cfg.texture_corr_m / max(mid_m * line_spacing_rad, 1e-9)),
        reverberation=reverb.astype(np.float32), display_gamma=cfg.display_gamma,
        display_soft_limit=bool(cfg.display_soft_limit),
        tail_decay=float(np.exp(-range_resolution_m / cfg.object_tail_m)) if cfg.object_tail_m else 0.0,
        tail_ratio=float(cfg.object_tail_ratio), object_rice_k=float(cfg.object_rice_k),
        back_wall_ratio=float(cfg.object_back_wall_ratio), back_wall_repeats=int(cfg.object_back_wall_repeats),
        specular_share=float(cfg.object_specular_share), specular_exponent=float(cfg.object_specular_exponent))
