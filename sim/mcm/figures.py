"""Summary and figures of an ``mcm_survey`` sweep (paper 003, Figs. 6-8).

* ``gospa.png``: mean GOSPA (cut-off 50 m, order 1, alpha 2) after each tile, per mapper;
* ``detections_vs_false.png``: mean correctly detected (within 20 m) versus false objects at
  the end, as the existence threshold E_th varies;
* ``cardinality.png``: mean number of confirmed objects after each tile;
* the summary: per mapper the mean final GOSPA, classification accuracy of the confirmed
  objects matched to a true one, and AUV position RMSE.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

LABELS = {"spa": "SPA (proposed)", "clairvoyant": "clairvoyant", "ins_plain": "INS-plain", "ins_filter": "INS-filter"}


def _modes(results: list[dict]) -> list[str]:
    return [m for m in LABELS if results and m in results[0]]


def summarise(results: list[dict]) -> dict:
    """Per-mapper means over runs (JSON-ready)."""
    out: dict = {"runs": len(results)}
    for m in _modes(results):
        acc_hits = sum((r[m]["class_accuracy"] or 0.0) * r[m]["class_matched"] for r in results)
        acc_n = sum(r[m]["class_matched"] for r in results)
        out[m] = {
            "final_gospa_mean": float(np.mean([r[m]["final_gospa"] for r in results])),
            "class_accuracy": acc_hits / acc_n if acc_n else None,
            "auv_rmse_m": float(np.sqrt(np.mean([r[m]["auv_rmse_m"] ** 2 for r in results]))),
            "final_cardinality_mean": float(np.mean([r[m]["cardinality"][-1] for r in results])),
        }
    if "spa" in out and "ins_filter" in out:
        out["spa_gospa_reduction_vs_ins_filter"] = 1.0 - out["spa"]["final_gospa_mean"] / out["ins_filter"][
            "final_gospa_mean"]
    return out


def write_figures(folder: Path, results: list[dict]) -> list[Path]:
    """Write the three PNGs into ``folder``; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    modes = _modes(results)
    for key, name, ylabel in (("gospa", "gospa.png", "GOSPA [m]"), ("cardinality", "cardinality.png",
                                                                      "confirmed objects")):
        fig, ax = plt.subplots(figsize=(6, 4))
        for m in modes:
            ax.plot(np.mean([r[m][key] for r in results], axis=0), label=LABELS[m])
        if key == "cardinality":
            if "n_objects" in results[0]:
                ax.axhline(results[0]["n_objects"], color="k", lw=0.5, ls="--", label="true objects")
        ax.set_xlabel("tile step")
        ax.set_ylabel(ylabel)
        ax.set_title(f"mcm_survey, {len(results)} runs")
        ax.legend()
        fig.tight_layout()
        fig.savefig(folder / name, dpi=100)
        plt.close(fig)
        paths.append(folder / name)
    fig, ax = plt.subplots(figsize=(6, 4))
    for m in modes:
        ax.plot(np.mean([r[m]["false"] for r in results], axis=0), np.mean([r[m]["correct"] for r in results], axis=0),
                marker=".", label=LABELS[m])
    ax.set_xlabel("false objects")
    ax.set_ylabel("correctly detected objects (within 20 m)")
    ax.set_title("end of mission, E_th in 0.02-0.99")
    ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "detections_vs_false.png", dpi=100)
    plt.close(fig)
    paths.append(folder / "detections_vs_false.png")
    return paths
