"""``auvsim dataset``: render a labelled, domain-randomised FLS (or side-scan) dataset."""

from __future__ import annotations

import argparse
import sys

from sim.cli.args import MAX_DATASET_FRAMES, frame_count, non_negative_int, positive_float, positive_int
from sim.cli.errors import CliError
from sim.process.cpus import usable_cpus


def _cmd_dataset(args: argparse.Namespace) -> int:
    from sim.dataset.generate import RANDOMIZATION_PRESETS, RAY_HINT, generate_dataset, generation_args
    from sim.dataset.spec import load_spec

    if args.heldout and args.randomization not in (None, "heldout"):
        raise CliError(f"--heldout and --randomization {args.randomization} contradict each other; give one "
                       "(--heldout is --randomization heldout)")
    if args.spec is not None:
        given = [opt for opt, v in (("--sensor sss", None if args.sensor in (None, "fls") else args.sensor),
                                    ("--randomization", args.randomization),
                                    ("--heldout", args.heldout or None), ("--tile-length", args.tile_length),
                                    ("--line-length", args.line_length)) if v is not None]
        if given:
            raise CliError(f"--spec {args.spec}: the spec sets the sonar and the scenes; leave out {', '.join(given)}")
    preset = "heldout" if args.heldout else (args.randomization or "train")
    kw = {}
    if args.spec is not None:
        kw = generation_args(load_spec(args.spec))
    elif args.sensor == "sss":
        from sim.dataset.sss_generate import SssSettings

        defaults = SssSettings()
        kw["settings"] = SssSettings(
            tile_length_m=defaults.tile_length_m if args.tile_length is None else args.tile_length,
            line_length_m=defaults.line_length_m if args.line_length is None else args.line_length)
    else:
        for opt, value in (("--tile-length", args.tile_length), ("--line-length", args.line_length)):
            if value is not None:
                raise CliError(f"{opt}: only with --sensor sss (side-scan tiles)")
    workers = args.workers
    if workers is not None and args.ray is None and workers > usable_cpus():
        workers = usable_cpus()  # more processes than CPUs render no faster, and each holds its own frames
        print(f"dataset: --workers {args.workers}: more than the CPUs this process may use ({workers}); "
              f"using {workers}", file=sys.stderr, flush=True)
    try:
        path = generate_dataset(args.out, args.n, seed=args.seed, workers=workers,
                                use_ray=args.ray is not None, ray_address=args.ray or None,
                                **{"randomization": RANDOMIZATION_PRESETS[preset], **kw},
                                progress=not args.no_progress)
    except ImportError as exc:
        if str(exc) == RAY_HINT:
            raise CliError(f"--ray: {RAY_HINT}") from None
        raise
    print(f"dataset: wrote {path}")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    from sim.dataset.generate import RANDOMIZATION_PRESETS

    p = sub.add_parser("dataset", help="render a labelled, domain-randomised FLS or side-scan dataset")
    p.add_argument("--n", type=frame_count, required=True,
                   help=f"number of frames, or side-scan tiles (1 to {MAX_DATASET_FRAMES})")
    p.add_argument("--spec", default=None, metavar="NAME|FILE.yaml",
                   help="dataset spec: a shipped one by name (fls_train, fls_wide, fls_heldout, "
                        "marine_debris_watertank) or a YAML file of your own (sonar, scenes, objects, formats)")
    p.add_argument("--sensor", choices=("fls", "sss"), default=None,
                   help="fls: forward-looking fan images (default); sss: side-scan waterfall tiles")
    p.add_argument("--tile-length", type=positive_float, default=None, metavar="M",
                   help="sss: along-track tile length, m (default 50)")
    p.add_argument("--line-length", type=positive_float, default=None, metavar="M",
                   help="sss: survey line per scene, m (default 150; line // tile tiles per scene)")
    p.add_argument("--out", required=True,
                   help="output folder: new, or a dataset folder to resume with the same arguments")
    p.add_argument("--seed", type=non_negative_int, default=0)
    p.add_argument("--workers", type=positive_int, default=None, help="local processes (default, and at most: the CPUs this process may use)")
    p.add_argument("--ray", nargs="?", const="", default=None, metavar="ADDRESS",
                   help="distribute with Ray (local instance, or the cluster at ADDRESS)")
    p.add_argument("--randomization", choices=sorted(RANDOMIZATION_PRESETS), default=None,
                   help="randomisation ranges preset (default train)")
    p.add_argument("--heldout", action="store_true",
                   help="use the held-out (distribution-shifted) randomisation ranges")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=_cmd_dataset)
