"""Compare this machine's FLS renders with the pinned reference, or write it anew.

The reference (``tests/data/fls_reference/``: ``labels.json`` and ``images.npz``, read by
``tests/sim/sensors/test_fls_frames_pinned.py`` and ``tests/sim/dataset/test_frames_pinned.py``)
holds the labels, image summaries and exact digests of the renders of
:data:`sim.bench.fls_reference.CASES`; labels must match exactly, images within the tolerance
of :mod:`sim.bench.fls_reference`.

    python scripts/fls_reference.py            # measure: per case the differences and the verdict
    python scripts/fls_reference.py --write    # regenerate after a deliberate change to the renderer

Prints one JSON object: per case and frame the measured image differences, the label
differences, whether the exact digest equals the pinned one, and whether this machine's
numerics fingerprint is the pinning machine's. Exit status 0, or 1 when a case is outside the
tolerance (after ``--write``: 0).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sim.cli.app import run_script, script_parser  # noqa: E402

DEFAULT_DIR = ROOT / "tests" / "data" / "fls_reference"


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and measure (or ``--write``) the reference; bad arguments: one line,
    exit status 2. Returns the exit status."""
    ap = script_parser("fls_reference.py", __doc__.splitlines()[0])
    ap.add_argument("--dir", type=Path, default=DEFAULT_DIR, help="reference folder (default tests/data/fls_reference)")
    ap.add_argument("--write", action="store_true", help="render the cases and write them as the reference")
    return run_script(ap, reference, argv)


def reference(args) -> int:
    """Measure or write the reference :func:`main` parsed ``args`` ask for."""
    from sim.cli.errors import CliError
    from sim.bench import fls_reference as fr
    if not args.write and not (args.dir / fr.LABELS_FILE).is_file():
        raise CliError(f"--dir {args.dir}: no {fr.LABELS_FILE} there (write one with --write)")
    got = {case: fr.render_case(case) for case in fr.CASES}
    if args.write:
        fr.write_reference(args.dir, got)
        print(json.dumps({"written": str(args.dir), "digests": {k: c.digest for k, c in got.items()}}, indent=1))
        return 0
    ref = fr.load_reference(args.dir)
    same_numerics = ref.fingerprint == fr.numerics_fingerprint()
    report, ok = {}, True
    for case, renders in got.items():
        if case not in ref.cases:
            report[case] = {"missing_from_reference": True}
            ok = False
            continue
        r = ref.cases[case]
        bad = fr.compare_case(r, renders)
        ok &= not bad
        report[case] = {"within_tolerance": not bad, "differences": bad,
                        "image_differences": [fr.image_differences(ri, gi) for ri, gi in zip(r.images, renders.images)],
                        "digest_equals_pinned": renders.digest == r.digest}
    print(json.dumps({"same_numerics_as_pinning_machine": same_numerics, "cases": report}, indent=1))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
