"""Regenerate the README's speed table from the benchmarks' JSON output.

Each row of the table is read from one benchmark's ``auvsim bench NAME --json`` object, saved
with the machine it ran on in ``docs/speed/<key>.json``. The table between the markers
``<!-- speed-table:begin -->`` and ``<!-- speed-table:end -->`` in README.md is replaced by
what this script makes of those files; nothing in it is typed by hand.

    python scripts/speed_table.py --run                # run every benchmark, save JSON, rewrite README
    python scripts/speed_table.py --run mission gym    # rerun some, keep the others' saved JSON
    python scripts/speed_table.py                      # rewrite README from the saved JSON only
    python scripts/speed_table.py --check              # exit 1 if README's table is not the saved JSON's

Benchmarks run one after another in fresh processes (``python -m sim.cli bench ...``); each
saved file records the command, the UTC time, the CPU count and the 1-minute load average,
because on a shared machine the load decides absolute figures (ratios measured within one run,
like ``workers_speedup``, hold better).
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
JSON_DIR = ROOT / "docs" / "speed"
README = ROOT / "README.md"
BEGIN, END = "<!-- speed-table:begin -->", "<!-- speed-table:end -->"


def _x(v: float) -> str:
    return f"{v:.0f}x" if v >= 20 else f"{v:.1f}x"


def _mission(r: dict) -> str:
    return f"{_x(r['real_time_factor'])} real time ({_x(r['cpu_real_time_factor'])} per CPU second)"


def _mission_workers(r: dict) -> str:
    w = r["workers"]
    out = (f"{_x(w['real_time_factor'])} real time, {w['workers_speedup']:.2f}x the serial loop of the same run "
           f"({_x(w['serial_real_time_factor'])})")
    if "cores_bound_real_time_factor" in w:  # what the processes' CPU times allow on the idle cores
        out += f"; CPU times allow {_x(w['cores_bound_real_time_factor'])}"
    return out


def _gym(variant: str) -> Callable[[dict], str]:
    return lambda r: f"{_x(r[variant]['real_time_factor'])} real time ({r[variant]['steps_per_s']:.0f} steps/s)"


def _gym_vector(variant: str) -> Callable[[dict], str]:
    def fmt(r: dict) -> str:
        v = r["vector"][variant]
        cpu = f", {v['cpu_speedup']:.2f}x by CPU time per step" if "cpu_speedup" in v else ""
        return (f"{_x(v['real_time_factor'])} real time over {v['n_envs']} envs, {v['speedup']:.2f}x one env "
                f"of the same run{cpu}")
    return fmt


def _fls(r: dict) -> str:
    out = f"{r['frames_per_s']:.0f} frames/s ({r['cpu_frames_per_s']:.0f} per CPU second) with the ground truth"
    if "no_truth" in r:  # the same frames as the closed loop renders them when no observer reads the truth
        b = r["no_truth"]
        same = "the same frames" if b["identical_frames"] else "FRAMES DIFFER"
        out += (f"; {b['frames_per_s']:.0f} frames/s ({b['cpu_frames_per_s']:.0f} per CPU second) without it, "
                f"as the mission renders when no observer reads it ({same})")
    return out


def _dataset(r: dict) -> str:
    one, n = r["one_worker"], r["n_workers"]
    return (f"{one['frames_per_s']:.1f} frames/s with 1 worker process ({one['cpu_frames_per_s']:.1f} per CPU second); "
            f"{n['workers']} workers {n['frames_per_s']:.1f} frames/s ({n['cpu_frames_per_s']:.1f} per CPU second), "
            f"{r['workers_speedup']:.2f}x one worker; {r['n_frames']} frames, start-up included "
            f"({r['startup']['cpu_s']:.2f} CPU s a worker)")


# key -> (bench arguments, [(row label, formatter of the JSON, goal)])
BENCHES: dict[str, tuple[list[str], list[tuple[str, Callable[[dict], str], str]]]] = {
    "physics": (["physics"], [
        ("`physics` (hull + Fossen + thrusters, 200 Hz)",
         lambda r: f"{_x(r['real_time_factor'])} real time ({r['us_per_step']:.1f} us/step; "
                   f"{_x(r['real_time_factor_cpu'])} per CPU second)", "200x")]),
    "fls": (["fls"], [
        ("`fls` (shipped setting)", _fls, ">= 150 frames/s")]),
    "mission_one_core": (["mission"], [
        ("`mission` full loop (FLS 3 Hz + CNN ATR + geolocalisation + PMHA), pinned to one core", _mission,
         ">= 20x (stretch 30x)")]),
    "mission": (["mission", "--workers", "2"], [
        ("`mission` full loop, serial (one process, free to use OpenCV's threads)", _mission, ""),
        ("`mission --workers 2` full loop, sonar and perception pipelined", _mission_workers, ">= 30x")]),
    "mission_no_sonar": (["mission", "--no-sonar"], [
        ("`mission --no-sonar` (physics, navigation sensors and filter, guidance, control), 1 core", _mission,
         ">= 80x")]),
    "gym": (["gym", "--workers", "2"], [
        ("`gym` Survey-v1 without sonar", _gym("survey"), ">= 150x"),
        ("`gym` Survey-v1 with sonar", _gym("survey_sonar"), ">= 20x"),
        ("`gym` Waypoint-v1", _gym("waypoint"), "200x"),
        ("`gym` Survey-v1 without sonar, `AsyncVectorEnv`", _gym_vector("survey"), ""),
        ("`gym` Survey-v1 with sonar, `AsyncVectorEnv`", _gym_vector("survey_sonar"), "")]),
    "dataset": (["dataset", "--workers", "2"], [
        ("`dataset` labelled FLS frames (PNG + COCO/YOLO labels), fresh processes", _dataset,
         ">= 30 per core, linear in workers")]),
    "pmha": (["pmha"], [
        ("`pmha` (50 anchors, 100 hypotheses)",
         lambda r: f"p50 {r['update_ms_p50']:.2f} ms, p99 {r['update_ms_p99']:.2f} ms", "p99 5 ms")]),
    "atr": (["atr"], [
        ("`atr` (CNN, onnxruntime, 1 thread)", lambda r: f"{r['cnn_frames_per_s']:.0f} frames/s", "50 (stretch 100)")]),
    "msis": (["msis"], [
        ("`msis` (Ping360, pool)", lambda r: f"{r['cpu_pings_per_s']:.0f} pings/s CPU time, feature extraction p99 "
                                             f"{r['features_p99_ms']:.2f} ms", "2000 pings/s, 2 ms")]),
    "sss": (["sss"], [
        ("`sss` (1000 bins per side)", lambda r: f"{r['cpu_pings_per_s']:.0f} pings/s CPU time", "1000 pings/s")]),
    "tracking": (["tracking"], [
        ("`tracking` (USBL + sonar EKF, 10 Hz tick)", lambda r: f"p50 {r['p50_ms']:.2f} ms, p99 {r['p99_ms']:.2f} ms",
         "p99 1 ms")]),
    "link": (["link"], [
        ("`link` (acoustic modem link, 10 Hz ticks, two vehicles)",
         lambda r: f"{r['link_us_per_message']:.0f} us per message, {r['link_us_per_tick_idle']:.1f} us per idle tick; "
                   f"encode {r['encode_us_per_message']:.0f} us, decode {r['decode_us_per_message']:.0f} us",
         "microseconds")]),
}


#: Benchmarks run pinned to one CPU (Linux ``sched_setaffinity``, as ``taskset -c N``): every
#: thread of the process (OpenCV's, BLAS's) then shares that core.
PINNED = {"mission_one_core"}


def run_bench(key: str, json_dir: Path = JSON_DIR) -> dict[str, Any]:
    """Run one benchmark in a fresh process and save its JSON with the machine's state."""
    args = BENCHES[key][0]
    cmd = [sys.executable, "-m", "sim.cli", "bench", *args, "--json"]
    load = os.getloadavg()[0]
    when = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    prefix, pin = "", None
    if key in PINNED:
        if not hasattr(os, "sched_setaffinity"):
            raise RuntimeError(f"benchmark {key} pins itself to one CPU: needs Linux (os.sched_setaffinity)")
        cpu = min(os.sched_getaffinity(0))
        prefix, pin = f"taskset -c {cpu} ", (lambda: os.sched_setaffinity(0, {cpu}))
    out = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=True, preexec_fn=pin)
    record = {"command": prefix + "auvsim bench " + " ".join(args) + " --json", "measured": when,
              "cpu_count": os.cpu_count(), "load_avg_1min_before": round(load, 2),
              "load_avg_1min_after": round(os.getloadavg()[0], 2),
              "result": json.loads(out.stdout.strip().splitlines()[-1])}
    json_dir.mkdir(parents=True, exist_ok=True)
    (json_dir / f"{key}.json").write_text(json.dumps(record, indent=1) + "\n")
    return record


def table(json_dir: Path = JSON_DIR) -> str:
    """The markdown table (markers included) from the saved JSON files; benchmarks without
    a file are left out."""
    rows = ["| benchmark | measured | goal | command, when, machine load |", "|---|---|---|---|"]
    for key, (_, lines) in BENCHES.items():
        path = json_dir / f"{key}.json"
        if not path.exists():
            continue
        rec = json.loads(path.read_text())
        where = (f"`{rec['command']}`, {rec['measured']}, {rec['cpu_count']} cores, load "
                 f"{rec['load_avg_1min_before']:.1f}-{rec['load_avg_1min_after']:.1f}")
        for label, fmt, goal in lines:
            rows.append(f"| {label} | {fmt(rec['result'])} | {goal} | {where} |")
    return "\n".join([BEGIN, *rows, END])


def rewrite_readme(readme: Path = README, json_dir: Path = JSON_DIR) -> bool:
    """Replace the table between the markers; True if the file changed.

    Raises:
        ValueError: the README lacks the markers.
    """
    text = readme.read_text()
    if BEGIN not in text or END not in text:
        raise ValueError(f"{readme}: no {BEGIN} ... {END} markers")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    new = head + table(json_dir) + tail
    if new != text:
        readme.write_text(new)
    return new != text


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--run", nargs="*", metavar="KEY", default=None,
                   help=f"run these benchmarks first (none named: all of {', '.join(BENCHES)})")
    p.add_argument("--check", action="store_true", help="only check that README's table is the saved JSON's")
    args = p.parse_args(argv)
    if args.check:
        text = README.read_text()
        ok = table() in text
        print("README speed table is up to date" if ok else "README speed table differs from docs/speed/*.json: "
              "run python scripts/speed_table.py")
        return 0 if ok else 1
    if args.run is not None:
        unknown = [k for k in args.run if k not in BENCHES]
        if unknown:
            print(f"--run: unknown benchmark {unknown[0]!r}; one of {', '.join(BENCHES)}", file=sys.stderr)
            return 2
        for key in args.run or list(BENCHES):
            print(f"bench {key} ...", flush=True)
            run_bench(key)
    changed = rewrite_readme()
    print("README.md speed table rewritten" if changed else "README.md speed table unchanged")
    return 0


if __name__ == "__main__":
    sys.exit(main())
