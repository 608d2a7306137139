"""The side-scan XTF file of a run read back from its bytes, drawn as a ground-range corrected
waterfall beside the simulator's own ground-range tile.

Flies ``mcm_survey_full`` (or ``--scenario``) for ``--duration-s`` with the XTF recorder
(``auvsim run ... --xtf``), then reads the file with the reader the tests write from the XTF
specification's byte layout (in ``tests/sim/outputs/test_xtf_log.py``, not ``pyxtf``), finds each
ping's first bottom return in its samples, corrects both channels to ground range over a flat
bed with that altitude, and draws the result next to the ground-range lines the simulator made
itself (``sensors.sss.ground_range: true``), with the altitude from the samples against the
simulated one. Prints the export's CPU cost per simulated minute.

Needs the ``xtf`` and ``test`` extras (pyxtf; pytest, which the test module imports).

Example: ``python scripts/xtf_waterfall.py --out docs/xtf_waterfall.png --duration-s 180``
"""

from __future__ import annotations

from pathlib import Path
import sys
import tempfile
import time

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from scenarios import load_scenario  # noqa: E402
from sim.bench.export import TimedObserver  # noqa: E402
from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.args import positive_float  # noqa: E402
from sim.cli.errors import CliError  # noqa: E402
from sim.events.records import ObserverBase  # noqa: E402
from sim.mission import Mission  # noqa: E402
from sim.outputs.xtf_log import XtfRecorder  # noqa: E402


def _spec_reader():
    """The XTF reader the tests write from the specification (``tests/sim/outputs/test_xtf_log.py``)."""
    import importlib.util

    path = ROOT / "tests" / "sim" / "outputs" / "test_xtf_log.py"
    module_spec = importlib.util.spec_from_file_location("xtf_spec_reader", path)
    module = importlib.util.module_from_spec(module_spec)
    sys.modules[module_spec.name] = module  # its dataclasses look themselves up there
    module_spec.loader.exec_module(module)
    return module


class _Own(ObserverBase):
    sonar_truth = False

    def __init__(self, name: str) -> None:
        self.name, self.ground, self.altitude = name, [], []

    def on_message(self, name, msg) -> None:
        if name == self.name and type(msg).__name__ == "SssRender" and msg.ping.ground_lines_u8 is not None:
            self.ground.append(msg.ping.ground_lines_u8)
            self.altitude.append(msg.ping.altitude_m)


def waterfall(port: np.ndarray, starboard: np.ndarray) -> np.ndarray:
    """(n_pings, 2 n) rows with port far range on the left, newest ping at the top."""
    return np.concatenate([port[:, ::-1], starboard], axis=1)[::-1]


def main(argv: list[str] | None = None) -> int:
    p = script_parser("xtf_waterfall.py", " ".join(__doc__.split("\n\n")[0].split()))
    p.add_argument("--scenario", default="mcm_survey_full", help="a scenario with a side-scan sonar")
    p.add_argument("--duration-s", type=positive_float, default=120.0, help="simulated seconds (default 120)")
    p.add_argument("--out", type=Path, required=True, help="the PNG to write (the docs' figure: docs/xtf_waterfall.png)")
    return run_script(p, figure, argv)


def figure(args) -> int:
    if args.out.suffix.lower() != ".png":
        raise CliError(f"--out {args.out}: give a .png file name")
    if args.out.is_dir():
        raise CliError(f"--out {args.out}: is a folder (give the PNG's file name)")
    if not args.out.parent.is_dir():
        raise CliError(f"--out {args.out}: its folder {args.out.parent} does not exist")
    scn = load_scenario(args.scenario, [f"duration_s={args.duration_s}"])
    name = next((n for n, c in scn.sensors.items() if c.kind == "sss" and c.enabled), None)
    if name is None:
        raise CliError(f"--scenario {args.scenario}: has no enabled sensor of kind sss (a side-scan sonar); "
                       "the shipped one with one: mcm_survey_full")
    scn = load_scenario(args.scenario, [f"duration_s={args.duration_s}", f"sensors.{name}.ground_range=true"])
    spec = _spec_reader()
    with tempfile.TemporaryDirectory() as tmp:
        own, recorder = _Own(name), TimedObserver(XtfRecorder(Path(tmp)))
        cpu0 = time.process_time()
        Mission(scn, observers=[own, recorder]).run(progress=False)
        run_cpu = time.process_time() - cpu0
        f = spec.read_xtf(Path(tmp) / f"{name}.xtf")
    minutes = args.duration_s / 60.0
    print(f"{len(f.pings)} pings, {len(f.navigation)} navigation packets; the export took "
          f"{recorder.cpu_s / minutes:.3f} CPU s per simulated minute, {recorder.cpu_s / run_cpu:.1%} of the run's "
          f"{run_cpu / minutes:.2f} CPU s per minute")

    n = len(f.pings[0].samples[0])
    bin_m = f.pings[0].channels[0]["SlantRange"] / n
    bottom = np.array([spec.first_bottom_bin(*pg.samples) for pg in f.pings], dtype=float)
    alt_from_samples = bottom * bin_m
    ground = np.stack([[spec.ground_range_line(pg.samples[s], bin_m, h, n) for s in range(2)]
                       for pg, h in zip(f.pings, alt_from_samples)])
    mine = waterfall(ground[:, 0], ground[:, 1])
    own_ground = np.stack(own.ground).astype(float)
    theirs = waterfall(own_ground[:, 0], own_ground[:, 1])
    t = np.arange(len(f.pings)) / float(scn.sensors[name].rate_hz)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 6), gridspec_kw={"width_ratios": [4, 4, 1.4]})
    extent = (-n * bin_m, n * bin_m, 0.0, t[-1])
    for ax, img, title in ((axes[0], mine, "from the XTF file's samples\n(specification reader, own bottom pick)"),
                           (axes[1], theirs, "the simulator's own ground-range lines")):
        ax.imshow(img, cmap="copper", extent=extent, aspect="auto", vmin=0, vmax=255, interpolation="nearest")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("ground range, m (port < 0 < starboard)")
    axes[0].set_ylabel("time, s (latest at the top)")
    axes[2].plot(alt_from_samples, t, lw=1.2, label="first bottom return\nin the file")
    axes[2].plot(own.altitude, t, "--", lw=1.0, label="simulated altitude")
    axes[2].set_xlabel("altitude, m")
    axes[2].legend(fontsize=7, loc="lower right")
    err = np.abs(alt_from_samples - np.asarray(own.altitude)) / bin_m
    fig.suptitle(f"{args.scenario}, {args.duration_s:g} s: {len(f.pings)} pings, bottom pick within "
                 f"{err.max():.1f} bins of the simulated altitude", fontsize=11)
    fig.tight_layout()
    fig.savefig(args.out, dpi=90)
    print(f"wrote {args.out}; bottom pick vs simulated altitude: max {err.max():.2f} bins, "
          f"mean {err.mean():.2f} bins ({bin_m * 100:.0f} cm bins)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
