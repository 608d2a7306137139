"""CPU time of single ``mcm_survey`` runs, and their results for comparing two versions.

Usage::

    PYTHONPATH=. python scripts/mcm_run_cpu.py N_PARTICLES OUT.json RUN [RUN ...] [--modes spa,ins_filter]

Prints per run the CPU and wall seconds and each mapper's final GOSPA / confirmed count, and
writes the full run results to OUT.json. Run it from two worktrees (alternately, on a shared
machine) and compare the JSON files (GOSPA per tile, cardinality, correct/false counts).
"""

from __future__ import annotations

import argparse
import json
import time

from sim.mcm.survey import McmSurveyConfig, run_survey


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n_particles", type=int)
    ap.add_argument("out")
    ap.add_argument("runs", type=int, nargs="+")
    ap.add_argument("--modes", default=None, help="comma-separated mappers (default: all four)")
    a = ap.parse_args()
    kw: dict = {"n_particles": a.n_particles}
    if a.modes:
        kw["modes"] = tuple(a.modes.split(","))
    cfg = McmSurveyConfig(**kw)
    rows = []
    for r in a.runs:
        t0, w0 = time.process_time(), time.perf_counter()
        res = run_survey(cfg, r)
        cpu, wall = time.process_time() - t0, time.perf_counter() - w0
        rows.append({"run": r, "cpu_s": cpu, "wall_s": wall, "res": res})
        print(f"run {r} cpu {cpu:.2f} s wall {wall:.2f} s " + " ".join(
            f"{m}:{res[m]['final_gospa']:.3f}/{res[m]['cardinality'][-1]}" for m in cfg.modes), flush=True)
    with open(a.out, "w") as f:
        json.dump(rows, f)


if __name__ == "__main__":
    main()
