"""A/B of the CNN detector inside a mission: this checkout's ``autonomy.atr`` against another's.

Flies the scenario (default ``cssn_lawnmower``, its seed) with this checkout's code; every FLS
frame goes through both detectors, in alternating order, and the mission continues with this
checkout's detections. Prints the number of frames whose detections differ (class, score, box
bytes, range, azimuth compared exactly) and the CPU time per ``detect`` of each (one
onnxruntime thread, as in the loop). Exit status 1 when any frame differs.

    python scripts/atr_detect_ab.py --other /path/to/main/checkout [--sim-s 300]

The other checkout's ``autonomy/atr`` is copied into a temporary package (its
``autonomy.atr`` imports renamed), so both versions load in one process.
"""

from __future__ import annotations

import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.args import positive_float  # noqa: E402
from sim.cli.errors import CliError  # noqa: E402


def load_other_atr(checkout: Path, tmp: Path):
    """The ``autonomy.atr`` package of ``checkout`` as module ``other_atr``."""
    src = checkout / "autonomy" / "atr"
    dst = tmp / "other_atr"
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("__pycache__"))
    for py in dst.glob("*.py"):
        py.write_text(re.sub(r"\bautonomy\.atr\b", "other_atr", py.read_text()))
    sys.path.insert(0, str(tmp))
    import other_atr  # noqa: F401
    from other_atr import build_detector
    from other_atr.config import AtrConfig

    return build_detector, AtrConfig


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and run the A/B; bad arguments, a checkout without ``autonomy/atr`` or an
    unknown scenario: one line, exit status 2. Returns the exit status (1 when frames differ)."""
    ap = script_parser("atr_detect_ab.py", __doc__.splitlines()[0])
    ap.add_argument("--other", required=True, type=Path, help="checkout holding the other autonomy/atr")
    ap.add_argument("--scenario", default="cssn_lawnmower", help="shipped scenario name or YAML file")
    ap.add_argument("--sim-s", type=positive_float, default=None,
                    help="simulated seconds (default: the whole mission)")
    return run_script(ap, ab, argv)


def ab(args) -> int:
    """The A/B of :func:`main`'s parsed ``args``; returns 1 when any frame's detections differ."""
    if not (args.other / "autonomy" / "atr" / "cnn_detector.py").is_file():
        raise CliError(f"--other {args.other}: not a checkout of this project (no autonomy/atr/cnn_detector.py there)")

    from scenarios.load import load_scenario
    from sim.mission import Mission

    with tempfile.TemporaryDirectory() as tmp:
        scenario = load_scenario(args.scenario)
        other_build, OtherCfg = load_other_atr(args.other, Path(tmp))
        mission = Mission(scenario)
        mission.reset()
        mine = mission.perception.detector
        other = other_build(OtherCfg(**mission.scenario.autonomy.atr.model_dump()))
        mine_detect = mine.detect
        cpu = {"this": 0.0, "other": 0.0}
        count = {"frames": 0, "differ": 0, "detections": 0}

        def key(dets):
            return [(d.t_s, d.class_name, d.score, d.box_xyxy_px.tobytes(), d.range_m, d.azimuth_rad) for d in dets]

        def detect(frame):
            pair = (("this", mine_detect), ("other", other.detect))
            out = {}
            for name, fn in pair if count["frames"] % 2 == 0 else pair[::-1]:
                t0 = time.process_time()
                out[name] = fn(frame)
                cpu[name] += time.process_time() - t0
            count["frames"] += 1
            count["detections"] += len(out["this"])
            count["differ"] += key(out["this"]) != key(out["other"])
            if count["frames"] % 300 == 0:
                print(f"{count['frames']} frames, t = {mission.t_s:.0f} s", file=sys.stderr, flush=True)
            return out["this"]

        mine.detect = detect
        if args.sim_s is None:
            mission.run(progress=False)
        else:
            for _ in range(int(round(args.sim_s / mission.autonomy_dt_s))):
                mission.step()
            mission.flush()
    n = max(count["frames"], 1)
    print(f"frames {count['frames']}, detections {count['detections']}, frames differing {count['differ']}; "
          f"CPU ms per detect: other {1000 * cpu['other'] / n:.3f}, this {1000 * cpu['this'] / n:.3f}, "
          f"ratio this/other {cpu['this'] / max(cpu['other'], 1e-12):.3f}")
    return 1 if count["differ"] else 0


if __name__ == "__main__":
    sys.exit(main())
