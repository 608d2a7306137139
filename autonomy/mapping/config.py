"""Config of the SPA mapper (paper 003, Section V; [P003] in ``docs/references.md``)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from autonomy.config_base import StrictModel

MapperMode = Literal["spa", "clairvoyant", "ins_plain", "ins_filter"]


class SpaMapperConfig(StrictModel):
    """SPA mapper parameters.

    Tile: each ping pair covers along-track ``[-tile_length_m, 0]`` behind the vehicle and
    ``tile_near_m .. tile_near_m + tile_width_m`` abeam on each side (vehicle frame).
    ``mode``: ``spa`` infers the vehicle state with the map; ``clairvoyant`` is given the true
    state; ``ins_plain`` takes the INS output as the state; ``ins_filter`` runs a particle filter
    on the INS only and maps from its mean (paper 003, Section V).
    """

    mode: MapperMode = "spa"
    n_particles: int = Field(1000, ge=10, le=100000)
    pd: float = Field(0.9, ge=0.0, le=1.0, description="probability of detection inside a tile")
    n_classes: Literal[2] = 2
    class_beta_1: tuple[float, float] = Field((6.0, 2.0), description="Beta(a, b) of pi^(1) given class 1")
    class_beta_2: tuple[float, float] = Field((2.0, 6.0), description="Beta(a, b) of pi^(1) given class 2")
    sigma_meas_m: float = Field(1.0, gt=0.0)
    clutter_mean: float = Field(0.1, gt=0.0, description="mean false alarms per tile pair (mu_0)")
    new_object_mean: float = Field(1e-3, gt=0.0, description="mean new objects per tile pair (mu_N)")
    prune_threshold: float = Field(1e-4, ge=0.0, lt=1.0, description="P_th")
    confirm_threshold: float = Field(0.8, gt=0.0, lt=1.0, description="E_th")
    tile_length_m: float = Field(50.0, gt=0.0)
    tile_width_m: float = Field(110.0, gt=0.0)
    tile_near_m: float = Field(20.0, ge=0.0)
    sigma_lin_mps2: float = Field(0.5, ge=0.0, description="NCT process noise, linear")
    sigma_ang_degps2: float = Field(20.0, ge=0.0, description="NCT process noise, angular")
    varsigma_p: float = Field(7.5, ge=0.0, description="INS position variance growth (sigma_p = 3 varsigma_p)")
    varsigma_h_deg_per_sqrt_h: float = Field(0.6, ge=0.0)
    nav_floor_pos_m: float = Field(1.0, gt=0.0, description="floor of the INS position std in the likelihood")
    nav_floor_heading_deg: float = Field(2.0, gt=0.0, description="floor of the INS heading std")
    merge_gate: float = Field(
        4.0, ge=0.0, description="merge two POs (existence > 0.05) whose means are closer than "
        "sqrt(merge_gate (var_1 + var_2 + 2 sigma_meas^2)); 0 disables (paper 003 does not merge)")
    roughening_k: float = Field(0.2, ge=0.0, description="Gordon's roughening constant K")
    bp_tol: float = Field(1e-5, gt=0.0)
