"""``auvsim realism``: measure real forward-looking sonar frames against a matched simulated set."""

from __future__ import annotations

import argparse
import json
import sys

from sim.cli.args import non_negative_int, positive_float, positive_int
from sim.cli.errors import CliError
from sim.outputs.run_dir import StagedOutput, check_output_dir


def _cmd_realism(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from sim.dataset.real_frames import RealDataError
    from sim.realism.report import FORMATIONS, realism_report, report_lines, side_by_side_png

    formations = ("before", "after") if args.formation == "both" else (
        tuple(FORMATIONS) if args.formation == "all" else (args.formation,))
    out = check_output_dir(args.out, kind="realism", overwrite=args.overwrite) if args.out else None
    if args.cnn:
        try:
            import torch  # noqa: F401
        except ImportError:
            raise CliError("--cnn: the small-CNN judge needs torch (pip install 'auvsim[train]')") from None
    try:
        import sklearn  # noqa: F401
    except ImportError:
        raise CliError("auvsim realism needs scikit-learn for its classifier judges "
                       "(pip install 'auvsim[realism]')") from None
    bars = []

    def progress(label: str, total: int):
        bar = tqdm(total=total, desc=label, unit="frame", disable=args.quiet or args.json, file=sys.stderr,
                   mininterval=1.0)
        bars.append(bar)

        def step(n: int = 1) -> None:
            bar.update(n)
            if bar.n >= total:
                bar.close()  # done: its rate and time stay those of its own frames
                if not (args.quiet or args.json):
                    print(f"{label}: done; measuring and judging", file=sys.stderr, flush=True)
        return step

    try:
        rep = realism_report(args.real, n_sim=args.frames, seed=args.seed, near_m=args.near_m,
                             formations=formations, cnn=args.cnn, limit_real=args.limit_real, progress=progress)
    except RealDataError as exc:
        msg = str(exc)
        raise CliError(msg if msg.startswith(("--real", "/")) or str(args.real) in msg
                       else f"--real {args.real}: {msg}") from None
    except ValueError as exc:
        msg = str(exc)
        if msg.startswith("near_m"):
            raise CliError("--near-m" + msg[len("near_m"):]) from None
        raise
    finally:
        for b in bars:
            b.close()
    data = rep.to_json()
    if out is not None:
        staged = StagedOutput(out, "realism")
        with staged as tmp:
            (tmp / "realism.json").write_text(json.dumps(data, indent=1))
            (tmp / "realism.txt").write_text("\n".join(report_lines(rep)) + "\n")
            side_by_side_png(rep, tmp / "side_by_side.png")
            side_by_side_png(rep, tmp / "simulated_only.png", include_real=False)
            staged.commit()
    if args.json:
        print(json.dumps(data))  # one line, the last
    else:
        print("\n".join(report_lines(rep)))
        if out is not None:
            print(f"wrote {out}/realism.json, realism.txt, side_by_side.png (with real frames), simulated_only.png")
    return 0


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("realism", help="measure real sonar frames against a matched simulated set",
                       description="Fit the real frames' fan, render matched water-tank scenes with the ARIS 3000 "
                                   "preset (fixed seed), and print image statistics, range profiles and classifier "
                                   "two-sample tests for real against simulated (docs/studies/realism.md).")
    p.add_argument("--real", required=True,
                   help="folder of real frames (images/*.png, optional masks/ and boxes/; without masks the object "
                        "measures are left out)")
    p.add_argument("--frames", type=positive_int, default=200, help="simulated frames per formation (default 200)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="root seed of scenes, noise and patches (default 0)")
    p.add_argument("--near-m", type=positive_float, default=0.7,
                   help="near range of the real window, m (sets the metric scale; default 0.7, the ARIS 3000's)")
    p.add_argument("--formation", choices=["before", "after", "shells", "both", "all"], default="both",
                   help="image formation to simulate: before (the preset's), after (the tank estimate), shells (the "
                        "tank estimate with objects as thin shells: specular lobe and far-wall echoes), both (before "
                        "and after; default), all")
    p.add_argument("--limit-real", type=positive_int, default=None, help="read at most this many real frames")
    p.add_argument("--cnn", action="store_true", help="add a small CNN as a second judge (needs torch)")
    p.add_argument("--out", default=None, help="folder for realism.json, realism.txt, side_by_side.png and simulated_only.png")
    p.add_argument("--overwrite", action="store_true", help="replace an earlier realism output in --out")
    p.add_argument("--json", action="store_true",
                   help="print the figures as one JSON object on the last line (no progress bars; null where "
                        "nothing was measured)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.set_defaults(func=_cmd_realism)
