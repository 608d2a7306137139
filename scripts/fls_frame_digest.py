"""SHA-256 digests of every byte an FLS render returns, on the bench sequence and on dataset scenes.

Run it on two versions of the code and compare the output: equal digests mean every frame is
byte-identical (:func:`sim.sensors.fls_digest.update_with_render`: fan and polar images,
polar and fan label masks, mean and realised intensities, each object's truth record, the
pose, and the noise generator's state after each frame). Hooks :meth:`sim.sensors.fls.FlsSensor.render`, then drives ``auvsim bench fls``'s
pose sequence (``--bench-frames``) and the first ``--dataset-frames`` frames of dataset scenes
(``--scenes`` of each of the ``train``, ``wide`` and ``heldout`` randomizations).

Usage: ``python scripts/fls_frame_digest.py [--bench-frames 60] [--scenes 4] [--dataset-frames 4]``
Prints one JSON object: a digest per part and ``all``.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.args import non_negative_int, positive_int  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and print the digests; bad arguments or an unknown scenario: one line,
    exit status 2. Returns the exit status."""
    ap = script_parser("fls_frame_digest.py", __doc__.splitlines()[0])
    ap.add_argument("--bench-frames", type=positive_int, default=60, help="frames of the bench pose sequence")
    ap.add_argument("--scenes", type=non_negative_int, default=4, help="dataset scenes of each randomization")
    ap.add_argument("--dataset-frames", type=positive_int, default=4, help="frames of each dataset scene")
    ap.add_argument("--scenario", default="cssn_lawnmower", help="shipped scenario name or YAML file (bench part)")
    return run_script(ap, digest, argv)


def digest(args) -> int:
    """Render and hash the frames :func:`main` parsed ``args`` ask for; print the JSON object."""
    from scenarios.load import load_scenario
    from sim.bench import fls as bench_fls
    from sim.dataset.generate import RANDOMIZATION_PRESETS, RenderSettings, fls_config, scene_spec
    from sim.dataset.scene_render import render_frames
    from sim.rng import component_rng
    from sim.sensors.fls import FlsSensor
    from sim.sensors.fls_digest import update_with_render

    scenario = load_scenario(args.scenario)  # a bad name fails before the hook is set
    current = {"h": None, "n": 0}
    inner = FlsSensor.render

    def hashed(self, *a, **kw):
        out = inner(self, *a, **kw)
        update_with_render(current["h"], out, self.rng)
        current["n"] += 1
        return out

    digests: dict[str, str] = {}
    frames: dict[str, int] = {}

    def part(name: str, fn) -> None:
        current["h"], current["n"] = hashlib.sha256(), 0
        fn()
        digests[name], frames[name] = current["h"].hexdigest(), current["n"]

    FlsSensor.render = hashed
    try:
        part("bench", lambda: bench_fls.run(scenario, args.bench_frames, without_truth=False, baseline=False))
        for rz_name in ("train", "wide", "heldout"):
            rz = RANDOMIZATION_PRESETS[rz_name]
            for i in range(args.scenes):
                spec = scene_spec(0, i, rz)
                part(f"{rz_name}/{i}", lambda: render_frames(spec, fls_config(spec, RenderSettings()),
                                                             component_rng(0, f"dataset/fls/{i}"),
                                                             args.dataset_frames))
    finally:
        FlsSensor.render = inner  # the process (a test calling main) keeps the real render
    total = hashlib.sha256("".join(f"{k}={v}" for k, v in digests.items()).encode()).hexdigest()
    print(json.dumps({"all": total, "frames": frames, "parts": digests}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
