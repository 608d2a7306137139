"""Render one FLS frame of a scenario with its ground-truth boxes into a PNG.

Usage: python scripts/render_fls_example.py [SCENARIO] --out PATH [--window NEAR FAR] [--altitude M]

``--out`` is required (no default that could overwrite a file); the README's figure is
regenerated with ``--out docs/fls_frame.png``.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from autonomy.frames import rot_from_euler
from scenarios import load_scenario
from scenarios.config.fls import FlsConfig
from sim.cli.app import run_script, script_parser
from sim.rng import component_rng
from sim.sensors.fls import FlsSensor
from sim.sensors.raycast import MujocoRayCaster
from sim.scene.world import build_world


def render(args) -> int:
    scenario = load_scenario(args.scenario)
    cfg = FlsConfig(**{**scenario.sensors.fls.model_dump(), "range_window_m": tuple(args.window)})
    world = build_world(scenario)
    caster = MujocoRayCaster(world.model, world.data, world.geom_object_id, world.geom_reflectivity,
                             world.vehicle_body_id)
    sensor = FlsSensor(cfg, np.zeros(3), component_rng(scenario.seed, "fls"))
    centroids = np.array([o.centroid_ned for o in world.objects])
    seabed_z = float(world.seabed.depth_at(*centroids[:, :2].mean(axis=0)))
    pos = np.array([centroids[:, 0].mean(), centroids[:, 1].min() - 6.0, seabed_z - args.altitude])
    out = sensor.render(0.0, pos, rot_from_euler(0.0, 0.0, np.pi / 2), caster, world.objects)

    img = cv2.applyColorMap(out.frame.fan, cv2.COLORMAP_BONE)
    for o in out.truth.objects:
        if o.bbox_xyxy is None:
            continue
        x0, y0, x1, y1 = np.round(o.bbox_xyxy).astype(int)
        color = (60, 220, 60) if o.visible else (60, 60, 230)
        cv2.rectangle(img, (x0 - 2, y0 - 2), (x1 + 2, y1 + 2), color, 1)
        cv2.putText(img, f"{o.name} {o.visible_fraction:.2f}", (x0, max(y0 - 6, 10)), cv2.FONT_HERSHEY_SIMPLEX,
                    0.4, color, 1, cv2.LINE_AA)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.out), img, [cv2.IMWRITE_PNG_COMPRESSION, 9])
    print(f"wrote {args.out} ({sum(o.visible for o in out.truth.objects)} visible objects)")
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = script_parser("render_fls_example.py", __doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default="cssn_lawnmower")
    ap.add_argument("--out", type=Path, required=True,
                    help="PNG to write (required; docs/fls_frame.png regenerates the README's figure)")
    ap.add_argument("--window", type=float, nargs=2, default=(1.0, 30.0), metavar=("NEAR", "FAR"))
    ap.add_argument("--altitude", type=float, default=2.0)
    return run_script(ap, render, argv)


if __name__ == "__main__":
    raise SystemExit(main())
