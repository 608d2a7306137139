"""The ``mcm_survey`` full mode: the MuJoCo hull, side-scan rendering and the onboard detector.

A scenario with ``mcm.mode: full`` (:class:`scenarios.config.mcm.McmConfig`; shipped:
``scenarios/mcm_survey_full.yaml``) flies its survey in the closed-loop mission; onboard, the
side-scan pings form a tile pair every ``tile_period_s`` (:class:`SssTileProcessor`: the
assembler and the highlight-shadow detector of :mod:`autonomy.sidescan`). :class:`McmFullObserver`
records the hull's true track and each tile's detections; :meth:`McmFullObserver.results`
then runs the same mappers and scores as the kinematic mode (:func:`sim.mcm.survey.map_and_score`)
with the paper's INS drift model (eqs. 28-30) applied to the true track at ``mcm.ins.rate_hz``
as the mappers' navigation input (the mappers are causal and see the INS outputs and tiles in
time order, exactly as online), and scores the detector against the rendered labels.
"""

from __future__ import annotations

from typing import Any

from sim.events.records import ObserverBase
import numpy as np
from numpy.typing import NDArray

from autonomy.mapping.spa_mapper import rotate_to_local
from autonomy.sidescan.detector import SssHighlightShadowDetector, SssTileDetections
from autonomy.sidescan.tile_assembler import SssTileAssembler
from scenarios.schema import Scenario
from sim.evaluation.world_model_score import match
from sim.mcm.errors import NoTileError
from sim.mcm.ins_drift import InsDriftParams, sample_drift
from sim.mcm.survey import map_and_score
from sim.rng import component_rng

FloatArray = NDArray[np.float64]


def no_tile_message(scenario: Scenario) -> str:
    """Why a run formed no tile and what to change (``duration_s``)."""
    period = scenario.mcm.tile.tile_period_s
    return (f"mcm: the run formed no side-scan tile in its {scenario.duration_s:g} s (duration_s; a tile pair "
            f"closes every mcm.tile.tile_period_s = {period:g} s of mission time while the side-scan pings, the "
            f"first at {period:g} s): raise duration_s above {period:g}")


class SssTileProcessor:
    """Onboard processing of the side-scan renders: the ping (never its labels) and the
    navigation estimate go to the tile assembler; a closed tile goes to the detector, whose
    :class:`SssTileDetections` is the result (None between tiles)."""

    def __init__(self, scenario: Scenario) -> None:
        self.assembler = SssTileAssembler(scenario.mcm.tile.tile_period_s)
        self.detector = SssHighlightShadowDetector(scenario.mcm.tile.detector)

    def __call__(self, render: Any, nav: Any) -> SssTileDetections | None:
        tile = self.assembler.add(render.ping, nav)
        return None if tile is None else self.detector.detect(tile)

    def reset(self) -> None:
        self.assembler.reset()


class McmFullObserver(ObserverBase):
    """Records what a full-mode run needs for mapping and scoring.

    Attributes:
        t_s, pos_ne, vel_ne, yaw_rad, turn_rate: the true track at every autonomy tick.
        tiles: the onboard detections per tile, in order.
        ping_t_s, ping_ids: each ping's time and the object ids labelled in it.
    """

    sonar_truth = False  # reads the side-scan's labels, not the forward-looking sonar's truth

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.sensor = scenario.mcm.sensor
        self.t_s: list[float] = []
        self.state: list[FloatArray] = []  # [north, east, v_north, v_east, turn rate, yaw]
        self.tiles: list[SssTileDetections] = []
        self.ping_t_s: list[float] = []
        self.ping_ids: list[NDArray[np.int16]] = []

    def on_start(self, info: Any) -> None:
        pass

    def on_end(self, summary: Any) -> None:
        pass

    def on_step(self, record: Any) -> None:
        tr = record.truth
        v = tr.R_nb @ tr.nu[:3]
        self.t_s.append(float(tr.t_s))
        self.state.append(np.array([tr.pos_ned[0], tr.pos_ned[1], v[0], v[1], tr.nu[5], tr.rpy_rad[2]]))

    def on_message(self, name: str, msg: Any) -> None:
        if name != self.sensor:
            return
        if isinstance(msg, SssTileDetections):
            self.tiles.append(msg)
        elif hasattr(msg, "labels"):
            lab = msg.ground_labels if msg.ground_labels is not None else msg.labels
            self.ping_t_s.append(float(msg.t_s))
            self.ping_ids.append(np.unique(lab[lab >= 0]).astype(np.int16))

    # -- after the run -------------------------------------------------------------------------
    def _true_at(self, t: FloatArray) -> FloatArray:
        """(len(t), 6) the recorded true [north, east, v_north, v_east, turn rate, yaw] at ``t``."""
        ts, S = np.asarray(self.t_s), np.asarray(self.state)
        cols = [np.interp(t, ts, S[:, j]) for j in range(5)]
        cols.append(np.interp(t, ts, np.unwrap(S[:, 5])))
        return np.column_stack(cols)

    def truth_objects(self) -> tuple[FloatArray, NDArray[np.intp]]:
        """(K, 2) true object positions (north, east) m and (K,) classes (0 mine-like), in id order."""
        tg = self.scenario.world.targets
        return (np.array([t.pos_ned[:2] for t in tg], dtype=float).reshape(-1, 2),
                np.array([0 if t.is_target else 1 for t in tg], dtype=np.intp))

    def detector_score(self) -> dict:
        """The detector against the labels: per tile, the objects labelled in its pings are the
        ones it should report; a detection within ``mcm.label_match_m`` of one (in the tile frame
        at the true pose) is correct. Returns pd, clutter per tile, mean ``pi`` per class."""
        pos, cls = self.truth_objects()
        period = self.scenario.mcm.tile.tile_period_s
        pt = np.asarray(self.ping_t_s)
        n_lab = n_hit = n_false = 0
        pi_by_class: list[list[float]] = [[], []]
        for tile in self.tiles:
            sel = (pt > (tile.tile_index - 1) * period + 1e-9) & (pt <= tile.t_s + 1e-9)
            ids = np.unique(np.concatenate([self.ping_ids[i] for i in np.flatnonzero(sel)] or [np.zeros(0, np.int16)]))
            ids = ids[ids < len(pos)]
            true = self._true_at(np.array([tile.t_s]))[0]
            ell_true = rotate_to_local(pos[ids] - true[:2], np.full(len(ids), true[5]))
            pairs = match(tile.ell_m, ell_true, max_dist_m=self.scenario.mcm.label_match_m)
            n_lab += len(ids)
            n_hit += len(pairs)
            n_false += len(tile.ell_m) - len(pairs)
            for i_det, i_lab, _ in pairs:
                pi_by_class[int(cls[ids[i_lab]])].append(float(tile.pi1[i_det]))
        n_tiles = max(len(self.tiles), 1)
        return {"tiles": len(self.tiles), "labelled": n_lab, "detected": n_hit,
                "pd": n_hit / n_lab if n_lab else None, "false": n_false, "clutter_per_tile": n_false / n_tiles,
                "mean_pi1_mine_like": float(np.mean(pi_by_class[0])) if pi_by_class[0] else None,
                "mean_pi1_other": float(np.mean(pi_by_class[1])) if pi_by_class[1] else None}

    def results(self, seed: int, run_index: int = 0, thresholds: FloatArray | None = None) -> dict:
        """The run's outputs in the kinematic mode's layout (:func:`sim.mcm.survey.run_survey`),
        plus ``detector`` (:meth:`detector_score`) and ``mode: full``.

        Raises:
            NoTileError: the run recorded no tile.
        """
        mcm = self.scenario.mcm
        if not self.tiles:
            raise NoTileError(no_tile_message(self.scenario))
        th = np.geomspace(0.02, 0.99, 20) if thresholds is None else np.asarray(thresholds, dtype=float)
        dt = 1.0 / mcm.ins.rate_hz
        t_nav = np.arange(dt, self.t_s[-1] + 1e-9, dt)
        true_nav = self._true_at(t_nav)
        p = mcm.ins
        drift, lam, iota = sample_drift(t_nav, true_nav[:, 5], component_rng(seed, "mcm/ins"),
                                        InsDriftParams(p.eps_p_m_per_h2, p.eps_h_deg_per_h, p.varsigma_p,
                                                       p.varsigma_h_deg_per_sqrt_h))
        g = true_nav[:, [0, 1, 5]] + drift
        t_tiles = np.array([t.t_s for t in self.tiles])
        truth_pos, truth_cls = self.truth_objects()

        def mapper_config(mode):
            return mcm.mapper.model_copy(update={"mode": mode})

        out: dict = {"run": int(run_index), "seed": int(seed), "mode": "full", "n_tiles": len(self.tiles),
                     "n_objects": int(len(truth_pos)), "lambda0_rad": lam, "iota": iota,
                     "sim_time_s": float(self.t_s[-1]), "pings": len(self.ping_t_s)}
        out.update(map_and_score(mapper_config, mcm.modes, seed, truth_pos, truth_cls, t_nav, g, t_tiles,
                                 [(t.ell_m, t.pi1) for t in self.tiles], self._true_at(t_tiles)[:, :5],
                                 self._true_at(np.array([0.0]))[0, :5], th, mcm.gospa_cutoff_m, mcm.correct_within_m))
        out["detector"] = self.detector_score()
        return out
