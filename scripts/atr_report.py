"""ATR models side by side on several labelled sets: the figures and PR curves of a model card.

For every (model, set): precision / recall at the model's operating threshold, AP50 and
AP50:95 (pycocotools), the precision-recall curve from a threshold sweep; the PNG draws paper
000's two operating points ([P000]: SSD 0.77 / 0.86, Mask R-CNN 0.95 / 0.82) on each set's
axes. Writes ``atr_report.json`` and ``atr_pr.png`` into ``--out``.

    python scripts/atr_report.py --model v2=autonomy/atr/models/atr_centernet.onnx \\
        --model v3=/tmp/atr_v3.onnx --set validation=DIR --set heldout=DIR --out /tmp/atr_report
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from autonomy.atr.cnn_detector import CnnDetector  # noqa: E402
from sim.evaluation.atr_metrics import evaluate_detector, threshold_sweep  # noqa: E402

PAPER_POINTS = {"SSD (paper 000)": (0.86, 0.77), "Mask R-CNN (paper 000)": (0.82, 0.95)}  # (recall, precision)
THRESHOLDS = np.round(np.arange(0.05, 0.96, 0.025), 3)


def _named(items: list[str], flag: str) -> dict[str, str]:
    out = {}
    for item in items:
        name, sep, path = item.partition("=")
        if not sep or not name or not path:
            raise SystemExit(f"atr_report: {flag} {item!r}: give NAME=PATH")
        out[name] = path
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", action="append", required=True, metavar="NAME=FILE.onnx")
    ap.add_argument("--set", dest="sets", action="append", required=True, metavar="NAME=DIR")
    ap.add_argument("--threshold", action="append", default=[], metavar="NAME=VALUE",
                    help="operating threshold of a model (default 0.40)")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    models, sets = _named(args.model, "--model"), _named(args.sets, "--set")
    thr = {k: float(v) for k, v in _named(args.threshold, "--threshold").items()}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    report: dict = {}
    for mname, mpath in models.items():
        det = CnnDetector(mpath, score_threshold=thr.get(mname, 0.40), classes=None)
        for sname, sdir in sets.items():
            point = evaluate_detector(det, sdir, det.score_threshold)
            curve = threshold_sweep(det, sdir, THRESHOLDS)
            report.setdefault(mname, {})[sname] = {
                "threshold": det.score_threshold,
                **{k: point[k] for k in ("precision", "recall", "false_alarms_per_frame", "ap50", "ap50_95",
                                         "ground_truth", "frames")},
                "curve": curve}
            print(f"{mname:6s} {sname:12s} P {point['precision']} R {point['recall']:.3f} "
                  f"AP50 {point['ap50']:.3f} AP50:95 {point['ap50_95']:.3f}", flush=True)
    (out / "atr_report.json").write_text(json.dumps(report, indent=1))

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(4.2 * len(sets), 4))
    FigureCanvasAgg(fig)
    for i, sname in enumerate(sets):
        ax = fig.add_subplot(1, len(sets), i + 1)
        for mname in models:
            c = report[mname][sname]["curve"]
            pts = [(r["recall"], r["precision"]) for r in c if r["precision"] is not None]
            ax.plot(*zip(*pts), marker=".", ms=3, lw=1.2, label=mname)
            op = report[mname][sname]
            if op["precision"] is not None:
                ax.plot(op["recall"], op["precision"], "o", mfc="none", color=ax.lines[-1].get_color())
        for label, (r, p) in PAPER_POINTS.items():
            ax.plot(r, p, "*", ms=10, label=label)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1.02)
        ax.set_xlabel("recall")
        ax.set_ylabel("precision")
        ax.set_title(sname)
        ax.grid(alpha=0.3)
        if i == 0:
            ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(out / "atr_pr.png", dpi=110)
    print(f"wrote {out / 'atr_report.json'} and {out / 'atr_pr.png'}")


if __name__ == "__main__":
    main()
