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


def _runs_text(n: int) -> str:
    return "1 run" if n == 1 else f"{n} runs"


def write_figures(folder: Path, results: list[dict], *, scenario: str = "mcm_survey",
                  title: str | None = None) -> list[Path]:
    """Write the three PNGs into ``folder``, titled ``title`` (default: ``scenario`` and the
    run count); returns their paths. Curves of few tile steps are drawn with markers, so a
    short run's single step shows."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import MaxNLocator

    paths = []
    modes = _modes(results)
    if title is None:
        title = f"{scenario}, {_runs_text(len(results))}" + (" (mean)" if len(results) > 1 else "")
    for key, name, ylabel in (("gospa", "gospa.png", "GOSPA [m]"), ("cardinality", "cardinality.png",
                                                                      "confirmed objects")):
        fig, ax = plt.subplots(figsize=(6, 4))
        for m in modes:
            curve = np.mean([r[m][key] for r in results], axis=0)
            ax.plot(np.arange(1, len(curve) + 1), curve, label=LABELS[m], marker="o" if len(curve) < 20 else None)
        if key == "cardinality":
            if "n_objects" in results[0]:
                ax.axhline(results[0]["n_objects"], color="k", lw=0.5, ls="--", label="true objects")
        ax.set_xlabel("tiles processed")
        n_steps = len(results[0][modes[0]][key]) if modes else 0
        if 0 < n_steps < 20:
            ax.set_xticks(range(1, n_steps + 1))
        else:
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_ylabel(ylabel)
        ax.set_title(title)
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
    ax.set_ylabel("correctly detected objects")
    ax.set_title(f"{title}: end of mission, E_th in 0.02-0.99")
    ax.legend()
    fig.tight_layout()
    fig.savefig(folder / "detections_vs_false.png", dpi=100)
    plt.close(fig)
    paths.append(folder / "detections_vs_false.png")
    return paths


def write_grid_figure(path: Path, scenario: str, rows: list[dict], runs: int) -> Path:
    """``grid_summary.png``: each mapper's mean final GOSPA (and the SPA's confirmed-object
    count) at every grid point. ``rows`` are ``grid_summary.json``'s points
    (``{"point", "folder", "summary"}``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [r["folder"].replace("__", "\n") for r in rows]
    modes = [m for m in LABELS if rows and m in rows[0]["summary"]]
    x = np.arange(len(rows))
    width = 0.8 / max(len(modes), 1)
    fig, ax = plt.subplots(figsize=(max(6.0, 1.2 * len(rows) + 2.0), 4.5))
    for k, m in enumerate(modes):
        ax.bar(x + (k - (len(modes) - 1) / 2) * width, [r["summary"][m]["final_gospa_mean"] for r in rows],
               width, label=LABELS[m])
    ax.set_xticks(x, labels, fontsize=8)
    ax.set_ylabel("mean final GOSPA [m]")
    ax.set_title(f"{scenario} grid, {_runs_text(runs)} per point")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.0, 1.0))
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def confirmed_objects_overlay(result: dict, mode: str = "spa"):
    """A ``map.png`` overlay (``draw(ax)``, East on x, North on y) of the objects ``mode``'s
    mapper confirmed at the end of a full-mode run (``result``: :func:`sim.mcm.survey.map_and_score`'s
    layout): mine-like as red crosses, others as black pluses; None when it has none."""
    pos = np.asarray(result.get(mode, {}).get("objects_ne_m", []), dtype=float).reshape(-1, 2)
    cls = np.asarray(result.get(mode, {}).get("objects_class", []), dtype=int)
    if not len(pos):
        return None

    def draw(ax) -> None:
        for k, (marker, colour, name) in enumerate((("x", "tab:red", "mine-like"), ("+", "k", "other"))):
            sel = pos[cls == k]
            if len(sel):
                ax.scatter(sel[:, 1], sel[:, 0], marker=marker, s=90, c=colour, linewidths=2, zorder=6,
                           label=f"{LABELS.get(mode, mode)} confirmed: {name}")

    return draw
