"""Resident memory of a long ``auvsim run`` against simulated time, extrapolated to 24 h.

Runs ``python -m sim.cli run`` (the real command, with its observers: trajectory log,
detection scoring, rerun recording unless ``--no-rerun``) in a child process whose stderr is a
pseudo-terminal, so its progress bar redraws twice a second with the simulated time. Every
``--sample-s`` wall seconds the ``VmRSS`` (``/proc/PID/status``, Linux) of the child and its
descendants (``--run-arg=--workers=2``: the sonar render and detection workers, where the
world model then lives) is summed and recorded with the latest simulated time; pages the
processes share (libraries) count once per process, so with workers the sum is an upper bound. At the end the samples after ``--warmup-s`` simulated seconds
are fitted with a straight line (least squares) and the line is extrapolated to 86400 s.
Samples after the simulated time stopped advancing (the run writing its outputs) are left out.

Writes into ``--out``: ``rss.csv`` (wall_s, sim_s, rss_mb; a row per sample as it is taken,
so a run stopped early keeps its samples; stopping the child ``auvsim run`` ends the
measurement and still writes the fit), ``rss.json (the fit, the 24 h
extrapolation, the command) and ``rss.png`` (RSS vs simulated time, the fit drawn over it);
the run's own outputs go to ``--out/run``.

    # 2.2 h CSSN-like survey with sonar, CNN ATR and world model: 54 legs of 70 m (the
    # mission's own time limit, 1 h by default, raised with it)
    python scripts/mission_memory.py --out /tmp/mem --duration-s 9000 \\
        --set autonomy.guidance.survey.origin_ne_m=[24,-18] --set autonomy.guidance.survey.length_m=70 \\
        --set autonomy.guidance.survey.width_m=53 --set autonomy.guidance.survey.leg_spacing_m=1 \\
        --set autonomy.guidance.survey.min_turn_radius_m=0.4 \\
        --set autonomy.guidance.mission.max_mission_time_s=9000

Exit status: the child's (0 done, 3 mission aborted; 2 when it refused an argument, its error
line repeated); 2 on bad input (one line, before any run).
"""

from __future__ import annotations

import argparse
import json
import os
import pty
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from scenarios.load import load_scenario  # noqa: E402
from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.args import non_negative_float, positive_float  # noqa: E402
from sim.cli.errors import CliError  # noqa: E402

DAY_S = 86400.0
_SIM_TIME = re.compile(rb"\((\d+) s, ")


def _rss_mb(pid: int) -> float | None:
    """``VmRSS`` of process ``pid`` in MB (10^6 bytes), None once it is gone."""
    try:
        with open(f"/proc/{pid}/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) * 1024 / 1e6
    except (FileNotFoundError, ProcessLookupError):
        return None
    return None


def _tree_rss_mb(pid: int) -> float | None:
    """Summed ``VmRSS`` (MB) of process ``pid`` and its descendants, None once ``pid`` is gone."""
    children: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue  # ended while listed
        children.setdefault(int(fields[1]), []).append(int(stat.parent.name))
    total = _rss_mb(pid)
    if total is None:
        return None
    todo = list(children.get(pid, []))
    while todo:
        p = todo.pop()
        total += _rss_mb(p) or 0.0
        todo += children.get(p, [])
    return total


def _last_line(path: Path) -> str:
    """The last non-empty line of a console capture (progress redraws split at carriage returns)."""
    try:
        text = path.read_bytes().decode("utf-8", "replace").replace("\r", "\n")
    except OSError:
        return ""
    lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
    return lines[-1] if lines else ""


class _SimClock:
    """Reads the child's progress bar from the pty master; ``sim_s`` the latest simulated time."""

    def __init__(self, fd: int, log: Path) -> None:
        self.sim_s = 0.0
        self._fd, self._log = fd, log
        self._thread = threading.Thread(target=self._read, daemon=True)
        self._thread.start()

    def _read(self) -> None:
        tail = b""
        with open(self._log, "wb") as log:
            while True:
                try:
                    chunk = os.read(self._fd, 4096)
                except OSError:  # the child closed its end
                    return
                if not chunk:
                    return
                log.write(chunk)
                tail = (tail + chunk)[-512:]
                hits = _SIM_TIME.findall(tail)
                if hits:
                    self.sim_s = float(hits[-1])


#: Below this many simulated seconds of samples after the warm-up the slope mostly measures
#: allocator steps and start-up, and its 24 h extrapolation is flagged as not meaningful.
MIN_FIT_WINDOW_S = 1800.0


def fit_growth(sim_s: np.ndarray, rss_mb: np.ndarray, warmup_s: float) -> dict[str, float]:
    """Least-squares line through the samples at ``sim_s >= warmup_s``: ``slope_mb_per_h``,
    the RSS it gives at 24 h (``rss_24h_mb``), the samples' min / max / last (MB), the
    simulated time they span (``fit_window_s``) and ``short_window`` (below
    :data:`MIN_FIT_WINDOW_S`).

    Raises:
        ValueError: fewer than 3 samples after the warm-up.
    """
    keep = sim_s >= warmup_s
    if int(keep.sum()) < 3:
        raise ValueError(f"only {int(keep.sum())} samples after the {warmup_s:g} s warm-up; run longer")
    slope, icpt = np.polyfit(sim_s[keep], rss_mb[keep], 1)
    window_s = float(sim_s[keep].max() - sim_s[keep].min())
    return {"warmup_s": warmup_s, "n_samples": int(keep.sum()), "fit_window_s": window_s,
            "short_window": window_s < MIN_FIT_WINDOW_S, "slope_mb_per_h": float(slope * 3600.0),
            "rss_24h_mb": float(icpt + slope * DAY_S), "rss_min_mb": float(rss_mb[keep].min()),
            "rss_max_mb": float(rss_mb[keep].max()), "rss_last_mb": float(rss_mb[-1]),
            "sim_s_last": float(sim_s[-1])}


def plot(path: Path, sim_s: np.ndarray, rss_mb: np.ndarray, fit: dict[str, float], title: str) -> None:
    """RSS vs simulated time (h) with the fitted line, PNG at ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(sim_s / 3600.0, rss_mb, ".", ms=3, label="VmRSS of the run's processes")
    t = np.array([fit["warmup_s"], sim_s[-1]])
    slope_s = fit["slope_mb_per_h"] / 3600.0
    icpt = fit["rss_24h_mb"] - slope_s * DAY_S
    ax.plot(t / 3600.0, icpt + slope_s * t, "r-",
            label=f"fit after {fit['warmup_s']:.0f} s: {fit['slope_mb_per_h']:+.2f} MB/h, "
                  f"24 h -> {fit['rss_24h_mb']:.0f} MB")
    ax.set_xlabel("simulated time (h)")
    ax.set_ylabel("resident memory (MB)")
    ax.set_title(title, fontsize=9)
    ax.set_ylim(0.0, max(600.0, float(rss_mb.max()) * 1.1))
    ax.axhline(500.0, color="k", ls=":", lw=0.8, label="24 h budget 500 MB")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def measure(args: argparse.Namespace) -> int:
    """Run and sample (see the module docstring); returns the child's exit status.

    Raises:
        CliError: ``--out`` exists, no ``/proc``; ScenarioError: the scenario or an override
            does not load (checked before the run starts).
    """
    if args.out.exists():
        raise CliError(f"--out {args.out}: exists; give a new folder")
    if args.warmup_s >= args.duration_s:
        raise CliError(f"--warmup-s {args.warmup_s:g}: must be below --duration-s {args.duration_s:g} "
                       "(the fit uses the samples after the warm-up)")
    for arg in args.run_arg:
        if arg.split("=")[0] in ("--quiet", "--out", "--overwrite"):
            raise CliError(f"--run-arg={arg}: not allowed (the measurement reads the run's progress display "
                           "and chooses its output folder)")
    if not Path("/proc/self/status").exists():
        raise CliError("mission_memory.py: needs Linux /proc to read VmRSS")
    load_scenario(args.scenario, [f"duration_s={args.duration_s:g}", *args.overrides])  # bad input: one line, now
    args.out.mkdir(parents=True)
    cmd = [sys.executable, "-m", "sim.cli", "run", args.scenario, "--out", str(args.out / "run"),
           "--set", f"duration_s={args.duration_s:g}"]
    for ov in args.overrides:
        cmd += ["--set", ov]
    cmd += args.run_arg
    master, slave = pty.openpty()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])))
    with open(args.out / "stdout.txt", "wb") as out:
        child = subprocess.Popen(cmd, stdout=out, stderr=slave, stdin=subprocess.DEVNULL, env=env, cwd=ROOT)
    os.close(slave)
    clock = _SimClock(master, args.out / "progress.txt")
    rows: list[tuple[float, float, float]] = []
    t0 = time.perf_counter()
    next_print = 0.0
    interrupted = False
    with open(args.out / "rss.csv", "w", encoding="ascii") as csv:
        csv.write("wall_s,sim_s,rss_mb\n")
        try:
            while child.poll() is None:
                rss = _tree_rss_mb(child.pid)
                if rss is not None and clock.sim_s > 0.0:
                    wall = time.perf_counter() - t0
                    rows.append((wall, clock.sim_s, rss))
                    csv.write(f"{wall:.3f},{clock.sim_s:.3f},{rss:.3f}\n")
                    csv.flush()
                    if wall >= next_print:
                        print(f"wall {wall:7.0f} s  sim {clock.sim_s:7.0f} s  RSS {rss:6.1f} MB", flush=True)
                        next_print = wall + 60.0
                time.sleep(args.sample_s)
        except KeyboardInterrupt:  # stop the run, keep its outputs, fit what was sampled
            interrupted = True
            print("mission_memory.py: interrupted; stopping the run and fitting the samples so far", file=sys.stderr)
            if child.poll() is None:
                child.send_signal(signal.SIGINT)
            try:
                child.wait(timeout=60)
            except subprocess.TimeoutExpired:
                child.kill()
    rc = child.wait()
    os.close(master)
    data = np.array(rows or [(0.0, 0.0, 0.0)], dtype=float)
    if np.any(data[:, 1] < data[-1, 1]):  # the mission only: not the output writing at its final time
        data = data[data[:, 1] < data[-1, 1]]
    result: dict = {"command": cmd, "returncode": rc}
    if rc not in (0, 3) and not rows:  # the run never started (a bad --run-arg): its own one-line error
        result["run_error"] = _last_line(args.out / "progress.txt")
        (args.out / "rss.json").write_text(json.dumps(result, indent=2) + "\n")
        print(f"mission_memory.py: error: the run failed before its first sample (exit status {rc}): "
              f"{result['run_error']}", file=sys.stderr)
        return rc
    try:
        result["fit"] = fit_growth(data[:, 1], data[:, 2], args.warmup_s)
    except ValueError as e:
        result["fit_error"] = str(e)
    (args.out / "rss.json").write_text(json.dumps(result, indent=2) + "\n")
    if "fit" in result:
        plot(args.out / "rss.png", data[:, 1], data[:, 2], result["fit"],
             f"auvsim run {args.scenario} ({' '.join(args.run_arg) or 'sonar, ATR, world model, rerun'})")
        f = result["fit"]
        print(f"RSS {f['rss_min_mb']:.1f}..{f['rss_max_mb']:.1f} MB over {f['warmup_s']:.0f}..{f['sim_s_last']:.0f} "
              f"sim s, slope {f['slope_mb_per_h']:+.2f} MB/h, 24 h extrapolated {f['rss_24h_mb']:.0f} MB; "
              f"{args.out / 'rss.png'}")
        if f["short_window"]:
            print(f"note: the fit spans only {f['fit_window_s']:.0f} simulated s after the warm-up (under "
                  f"{MIN_FIT_WINDOW_S:.0f} s): the slope and its 24 h extrapolation are not meaningful; "
                  "run longer (--duration-s)", file=sys.stderr)
    else:
        print(result["fit_error"], file=sys.stderr)
    return 130 if interrupted else rc


def main(argv: list[str] | None = None) -> int:
    p = script_parser("mission_memory.py", __doc__.splitlines()[0])
    p.add_argument("scenario", nargs="?", default="cssn_lawnmower")
    p.add_argument("--out", required=True, type=Path, help="new folder for rss.csv/json/png and the run")
    p.add_argument("--duration-s", type=positive_float, default=9000.0, help="simulated mission length, s")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="scenario override passed to auvsim run (repeatable)")
    p.add_argument("--sample-s", type=positive_float, default=2.0, help="wall seconds between RSS samples")
    p.add_argument("--warmup-s", type=non_negative_float, default=600.0,
                   help="simulated seconds left out of the fit")
    p.add_argument("--run-arg", action="append", default=[], metavar="ARG",
                   help="extra argument for auvsim run, e.g. --run-arg=--no-rerun (repeatable)")
    return run_script(p, measure, argv)


if __name__ == "__main__":
    sys.exit(main())
