"""The ``mcm_survey`` scenario of paper 003 in its fast kinematic mode.

The vehicle follows the planned lawnmower exactly (1.5 m/s, legs along north), the INS
reports ``[north, east, heading] + drift`` at 1 Hz (:mod:`sim.mcm.ins_drift`), and every
``tile_period_s`` a tile pair yields detection-level ATR output
(:mod:`sim.mcm.tile_detections`). The four mappers of paper 003 (SPA, clairvoyant,
INS-plain, INS-filter; :class:`autonomy.mapping.spa_mapper.SpaMapper`) run on the same
truth, INS and detections. Per run: GOSPA (cut-off 50 m, order 1, alpha 2) and cardinality
after each tile, the vehicle position error, and at the end correct versus false confirmed
objects over a range of existence thresholds and the classification accuracy.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from autonomy.config_base import StrictModel
from autonomy.mapping.config import MapperMode, SpaMapperConfig
from autonomy.mapping.spa_mapper import SpaMapper
from sim.evaluation.world_model_score import gospa, match
from sim.mcm.ins_drift import InsDriftParams, sample_drift
from sim.mcm.tile_detections import TileDetector
from sim.rng import component_rng

FloatArray = NDArray[np.float64]
MODES: tuple[MapperMode, ...] = ("spa", "clairvoyant", "ins_plain", "ins_filter")
DEFAULT_MLOS = ((80.0, 120.0), (160.0, 400.0), (250.0, 250.0), (370.0, 90.0), (430.0, 330.0))


class McmSurveyConfig(StrictModel):
    """The ``mcm_survey`` scenario (paper 003, Section V; [P003] in ``docs/references.md``).

    Objects: ``mine_like_ned`` fixed, ``n_other`` others re-drawn uniformly over the
    ``area_side_m`` square each run. Survey: ``n_lanes`` legs along north of ``area_side_m``,
    ``lane_spacing_m`` apart from ``first_lane_east_m``, joined by half circles, at ``speed_mps``.
    """

    seed: int = Field(0, ge=0)
    mode: Literal["kinematic"] = "kinematic"
    area_side_m: float = Field(500.0, gt=0.0)
    mine_like_ned: tuple[tuple[float, float], ...] = DEFAULT_MLOS
    n_other: int = Field(45, ge=0, le=10000)
    speed_mps: float = Field(1.5, gt=0.0, le=10.0)
    lane_spacing_m: float = Field(20.0, gt=0.0)
    first_lane_east_m: float = -30.0
    n_lanes: int = Field(29, ge=1, le=1000)
    tile_period_s: float = Field(33.0, gt=0.0)
    nav_rate_hz: float = Field(1.0, gt=0.0, le=100.0)
    pd: float = Field(0.9, ge=0.0, le=1.0)
    clutter_mean: float = Field(0.1, ge=0.0)
    sigma_meas_m: float = Field(1.0, gt=0.0)
    class_beta_1: tuple[float, float] = (6.0, 2.0)
    class_beta_2: tuple[float, float] = (2.0, 6.0)
    tile_length_m: float = Field(50.0, gt=0.0)
    tile_width_m: float = Field(110.0, gt=0.0)
    tile_near_m: float = Field(20.0, ge=0.0)
    eps_p_m_per_h2: float = Field(7.5, ge=0.0)
    eps_h_deg_per_h: float = Field(1.0, ge=0.0)
    varsigma_p: float = Field(7.5, ge=0.0)
    varsigma_h_deg_per_sqrt_h: float = Field(0.6, ge=0.0)
    n_particles: int = Field(1000, ge=10, le=100000)
    sigma_lin_mps2: float = Field(0.5, ge=0.0, description="mapper's NCT process noise, linear")
    sigma_ang_degps2: float = Field(20.0, ge=0.0, description="mapper's NCT process noise, angular")
    confirm_threshold: float = Field(0.8, gt=0.0, lt=1.0)
    modes: tuple[MapperMode, ...] = Field(MODES, min_length=1, description="the mappers to run (at least one)")
    gospa_cutoff_m: float = Field(50.0, gt=0.0)
    correct_within_m: float = Field(20.0, gt=0.0)
    max_tiles: int | None = Field(None, ge=1, description="stop after this many tiles (None: the survey)")

    @model_validator(mode="after")
    def _check(self) -> "McmSurveyConfig":
        if self.tile_length_m > self.survey_length_m:
            raise ValueError(f"tile_length_m {self.tile_length_m} is longer than the survey "
                             f"({self.survey_length_m:.0f} m of track)")
        if self.speed_mps * self.tile_period_s > 2.0 * self.tile_length_m:
            raise ValueError("tiles leave gaps: speed_mps * tile_period_s > 2 tile_length_m")
        return self

    @property
    def survey_length_m(self) -> float:
        """Track length, m (legs and half-circle turns)."""
        return self.n_lanes * self.area_side_m + (self.n_lanes - 1) * 0.5 * np.pi * self.lane_spacing_m

    def mapper_config(self, mode: MapperMode) -> SpaMapperConfig:
        return SpaMapperConfig(
            mode=mode, n_particles=self.n_particles, pd=max(self.pd, 1e-6), class_beta_1=self.class_beta_1,
            class_beta_2=self.class_beta_2, sigma_meas_m=self.sigma_meas_m,
            clutter_mean=max(self.clutter_mean, 1e-6), tile_length_m=self.tile_length_m,
            tile_width_m=self.tile_width_m, tile_near_m=self.tile_near_m, varsigma_p=self.varsigma_p,
            varsigma_h_deg_per_sqrt_h=self.varsigma_h_deg_per_sqrt_h, confirm_threshold=self.confirm_threshold,
            sigma_lin_mps2=self.sigma_lin_mps2, sigma_ang_degps2=self.sigma_ang_degps2)


class LawnmowerPath:
    """Planned path, followed exactly: legs along north joined by half-circle turns of radius
    ``lane_spacing_m / 2``, at constant speed (NED north, east, m)."""

    def __init__(self, cfg: McmSurveyConfig) -> None:
        self.speed = cfg.speed_mps
        r = 0.5 * cfg.lane_spacing_m
        segs = []  # (north0, east0, heading0, length, curvature)
        for k in range(cfg.n_lanes):
            e = cfg.first_lane_east_m + k * cfg.lane_spacing_m
            north_bound = k % 2 == 0
            n0, psi = (0.0, 0.0) if north_bound else (cfg.area_side_m, np.pi)
            segs.append((n0, e, psi, cfg.area_side_m, 0.0))
            if k + 1 < cfg.n_lanes:
                segs.append((cfg.area_side_m - n0, e, psi, np.pi * r, (1.0 if north_bound else -1.0) / r))
        self.segs = np.array(segs)
        self.cum = np.concatenate([[0.0], np.cumsum(self.segs[:, 3])])
        self.duration_s = float(self.cum[-1] / cfg.speed_mps)

    def state(self, t_s: FloatArray) -> FloatArray:
        """(T, 5) true states [north, east, v_north, v_east, turn rate] at times (T,) s."""
        s = np.clip(np.asarray(t_s, dtype=float).reshape(-1) * self.speed, 0.0, self.cum[-1])
        i = np.clip(np.searchsorted(self.cum, s, side="right") - 1, 0, len(self.segs) - 1)
        n0, e0, psi0, _, kappa = self.segs[i].T
        u = s - self.cum[i]
        psi = psi0 + kappa * u
        straight = kappa == 0.0
        safe = np.where(straight, 1.0, kappa)
        dn = np.where(straight, u * np.cos(psi0), (np.sin(psi) - np.sin(psi0)) / safe)
        de = np.where(straight, u * np.sin(psi0), -(np.cos(psi) - np.cos(psi0)) / safe)
        return np.column_stack([n0 + dn, e0 + de, self.speed * np.cos(psi), self.speed * np.sin(psi),
                                self.speed * kappa])


def run_survey(cfg: McmSurveyConfig, run_index: int, thresholds: FloatArray | None = None) -> dict:
    """One Monte Carlo run of every mapper in ``cfg.modes`` on one draw of objects and drift.

    The run's randomness comes from ``component_rng(cfg.seed + run_index, ...)`` only, so a
    run's result does not depend on which worker runs it or in what order.

    Returns:
        JSON-ready dict: ``run``, ``seed``, ``n_tiles``, ``n_objects``, ``lambda0_rad``, ``iota``, and per mode
        ``gospa`` (per tile), ``cardinality`` (per tile), ``auv_err_m`` (per tile),
        ``final_gospa``, ``auv_rmse_m``, ``class_accuracy``, ``correct`` / ``false`` (per
        threshold of ``thresholds``, default 20 log-spaced in 0.02-0.99).
    """
    seed = int(cfg.seed) + int(run_index)
    th = np.geomspace(0.02, 0.99, 20) if thresholds is None else np.asarray(thresholds, dtype=float)
    rng_obj = component_rng(seed, "mcm/objects")
    mlo = np.asarray(cfg.mine_like_ned, dtype=float).reshape(-1, 2)
    other = rng_obj.uniform(0.0, cfg.area_side_m, (cfg.n_other, 2))
    truth_pos = np.concatenate([mlo, other])
    truth_cls = np.concatenate([np.zeros(len(mlo), int), np.ones(len(other), int)])
    path = LawnmowerPath(cfg)
    dt_nav = 1.0 / cfg.nav_rate_hz
    t_nav = np.arange(dt_nav, path.duration_s + 1e-9, dt_nav)
    truth_nav = path.state(t_nav)
    drift, lam, iota = sample_drift(t_nav, np.arctan2(truth_nav[:, 3], truth_nav[:, 2]),
                                    component_rng(seed, "mcm/ins"),
                                    InsDriftParams(cfg.eps_p_m_per_h2, cfg.eps_h_deg_per_h, cfg.varsigma_p,
                                                   cfg.varsigma_h_deg_per_sqrt_h))
    g = np.column_stack([truth_nav[:, :2], np.arctan2(truth_nav[:, 3], truth_nav[:, 2])]) + drift
    n_tiles = int(path.duration_s // cfg.tile_period_s)
    if cfg.max_tiles is not None:
        n_tiles = min(n_tiles, cfg.max_tiles)
    t_tiles = cfg.tile_period_s * np.arange(1, n_tiles + 1)
    detector = TileDetector(cfg, component_rng(seed, "mcm/atr"))
    tiles = [detector.detect(path.state(np.array([t]))[0], truth_pos, truth_cls) for t in t_tiles]
    out: dict = {"run": int(run_index), "seed": seed, "n_tiles": n_tiles, "n_objects": int(len(truth_pos)),
                 "lambda0_rad": lam, "iota": iota}
    true_at_tiles = path.state(t_tiles)
    out.update(map_and_score(cfg.mapper_config, cfg.modes, seed, truth_pos, truth_cls, t_nav, g, t_tiles, tiles,
                             true_at_tiles, path.state(np.array([0.0]))[0], th, cfg.gospa_cutoff_m,
                             cfg.correct_within_m))
    return out


def map_and_score(mapper_config, modes, seed: int, truth_pos: FloatArray, truth_cls: NDArray[np.intp],
                  t_nav: FloatArray, g: FloatArray, t_tiles: FloatArray, tiles: list[tuple[FloatArray, FloatArray]],
                  true_at_tiles: FloatArray, initial_state: FloatArray, thresholds: FloatArray,
                  gospa_cutoff_m: float, correct_within_m: float) -> dict:
    """Run each mapper of ``modes`` over one survey's INS outputs and tile detections, and
    score it (paper 003, Section V; shared by the kinematic and the full mode).

    Args:
        mapper_config: mode -> :class:`SpaMapperConfig`.
        modes: the mappers to run; seed: the run's seed (mapper ``component_rng`` streams).
        truth_pos: (K, 2) true objects (north, east) m; truth_cls: (K,) 0 mine-like, 1 other.
        t_nav: (T,) INS output times, s; g: (T, 3) INS outputs (north m, east m, heading rad).
        t_tiles: (N,) tile times, s; tiles: N pairs ``(ell (M, 2) tile frame m, pi1 (M,))``.
        true_at_tiles: (N, 5) true states [north, east, v_north, v_east, turn rate] at the tiles.
        initial_state: (5,) the known start state.
        thresholds: existence thresholds for correct / false counts.
        gospa_cutoff_m, correct_within_m: GOSPA cut-off c (p 1, alpha 2); match radius, m.

    Returns:
        per mode: ``gospa``, ``cardinality``, ``auv_err_m`` (per tile), ``final_gospa``,
        ``auv_rmse_m``, ``class_accuracy``, ``class_matched``, ``correct``, ``false``, and the
        objects confirmed at the end (at the mapper's ``confirm_threshold``): ``objects_ne_m``
        (J, 2) north, east m and ``objects_class`` (J,) 0 mine-like; and ``thresholds``.
    """
    out: dict = {}
    for mode in modes:
        mapper = SpaMapper(mapper_config(mode), initial_state, component_rng(seed, f"mcm/mapper/{mode}"))
        gos, card, err = [], [], []
        k_nav = 0
        for t_tile, (ell, pi1), true_state in zip(t_tiles, tiles, true_at_tiles):
            k_end = int(np.searchsorted(t_nav, t_tile + 1e-9, side="right"))  # INS outputs up to the tile
            mapper.nav_updates(t_nav[k_nav:k_end], g[k_nav:k_end])
            k_nav = max(k_nav, k_end)
            mapper.set_true_state(true_state)
            mapper.tile_update(ell, pi1)
            est = mapper.estimate()
            gos.append(gospa(est.pos_ned, truth_pos, c=gospa_cutoff_m, p=1.0))
            card.append(int(len(est.pos_ned)))
            err.append(float(np.linalg.norm(mapper.vehicle_estimate()[:2] - true_state[:2])))
        correct, false = [], []
        acc_hits = acc_n = 0
        for e_th in thresholds:
            est = mapper.estimate(float(e_th))
            pairs = match(est.pos_ned, truth_pos, max_dist_m=correct_within_m)
            correct.append(len(pairs))
            false.append(int(len(est.pos_ned) - len(pairs)))
        est = mapper.estimate()
        for i_est, i_tru, _ in match(est.pos_ned, truth_pos, max_dist_m=correct_within_m):
            acc_n += 1
            acc_hits += int(est.class_index[i_est] == truth_cls[i_tru])
        out[mode] = {
            "gospa": gos, "cardinality": card, "auv_err_m": err, "final_gospa": gos[-1] if gos else None,
            "auv_rmse_m": float(np.sqrt(np.mean(np.square(err)))) if err else None,
            "class_accuracy": acc_hits / acc_n if acc_n else None, "class_matched": acc_n,
            "correct": correct, "false": false,
            "objects_ne_m": np.asarray(est.pos_ned, dtype=float).reshape(-1, 2).tolist(),
            "objects_class": np.asarray(est.class_index, dtype=int).tolist(),
        }
    out["thresholds"] = np.asarray(thresholds, dtype=float).tolist()
    return out
