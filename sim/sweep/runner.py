"""Resumable Monte Carlo sweeps (``auvsim sweep``).

A sweep folder holds ``sweep.json`` (what is swept: scenario, overrides, seed, run count), one
``runs/run_NNNNN.json`` per finished run (written atomically, so an interrupted sweep keeps
every finished run), then ``results.jsonl`` (one line per run, in run order), ``summary.json``
and the scenario's figures. Restarting with the same arguments redoes only the missing runs;
different arguments are refused. Run ``i`` draws from ``component_rng(seed + i, ...)`` only, so
results do not depend on the number of workers or the order runs finish in.

Runs execute in this process (one worker), in local processes (``workers > 1``) or on Ray
(a local instance, or the cluster at an address).
"""

from __future__ import annotations

import difflib
import json
import os
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from sim.outputs.run_dir import OutputDirError, check_output_dir, is_output_of, write_marker
from sim.mcm.figures import summarise, write_figures, write_grid_figure

if TYPE_CHECKING:
    from scenarios.schema import Scenario

RAY_HINT = "--ray needs Ray: pip install 'auvsim[scale]' (or pip install ray)"
SWEEP_KIND = "sweep"
GRID_KIND = "sweep-grid"


class SweepError(ValueError):
    """Bad sweep input (unknown scenario, bad override, unreachable Ray address, mismatch)."""


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep runs: ``scenario`` with ``overrides`` (dotted key -> value), ``runs`` runs
    from ``seed``."""

    scenario: str
    runs: int
    seed: int
    overrides: dict[str, Any]

    def as_json(self) -> dict:
        return {"scenario": self.scenario, "runs": self.runs, "seed": self.seed, "overrides": self.overrides}


def parse_overrides(items: list[str]) -> dict[str, Any]:
    """``key=value`` strings (values parsed as YAML) -> dict.

    Raises:
        SweepError: an item has no ``=`` or an unparsable value.
    """
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SweepError(f"--set {item!r}: expected KEY=VALUE")
        try:
            out[key.strip()] = yaml.safe_load(value)
        except yaml.YAMLError as exc:
            raise SweepError(f"--set {item!r}: value is not valid YAML ({exc.__class__.__name__})") from None
    return out


def parse_grid(items: list[str]) -> dict[str, list[Any]]:
    """``key=v1,v2,...`` strings (each value parsed as YAML), or the path of a YAML file
    mapping keys to value lists -> ordered dict of value lists.

    Raises:
        SweepError: an item without ``=`` or values, a key given twice, an unparsable value,
            a grid file that is missing or not a mapping of lists.
    """
    grid: dict[str, list[Any]] = {}
    for item in items:
        if "=" not in item and item.endswith((".yaml", ".yml")):
            try:
                data = yaml.safe_load(Path(item).read_text())
            except (OSError, yaml.YAMLError) as exc:
                raise SweepError(f"--grid {item}: cannot read it as YAML ({exc.__class__.__name__})") from None
            if not isinstance(data, dict) or not all(isinstance(v, list) and v for v in data.values()):
                raise SweepError(f"--grid {item}: expected a mapping of keys to non-empty value lists")
            for key, values in data.items():
                if key in grid:
                    raise SweepError(f"--grid {key}: given twice")
                grid[str(key)] = list(values)
            continue
        key, sep, values = item.partition("=")
        key = key.strip()
        if not sep or not key or not values.strip():
            raise SweepError(f"--grid {item!r}: expected KEY=V1,V2,...")
        if key in grid:
            raise SweepError(f"--grid {key}: given twice")
        try:
            grid[key] = [yaml.safe_load(v) for v in values.split(",")]
        except yaml.YAMLError as exc:
            raise SweepError(f"--grid {item!r}: a value is not valid YAML ({exc.__class__.__name__})") from None
    return grid


def grid_points(grid: dict[str, list[Any]]) -> list[dict[str, Any]]:
    """The grid's points (cartesian product, first key slowest) as override dicts."""
    import itertools

    keys = list(grid)
    return [dict(zip(keys, combo)) for combo in itertools.product(*(grid[k] for k in keys))]


def point_folder_name(point: dict[str, Any]) -> str:
    """A folder name for a grid point, e.g. ``n_particles=300__pd=0.9``."""
    return "__".join(f"{k}={json.dumps(v).strip(chr(34))}" for k, v in point.items()) or "base"


def run_grid(out: str | os.PathLike[str], spec: SweepSpec, grid: dict[str, list[Any]], **kwargs: Any) -> dict:
    """Run (or resume) ``spec`` at every point of ``grid``: one sweep folder per point under
    ``out`` (resumable as :func:`run_sweep`), then ``grid_summary.json`` listing each point's
    overrides and summary and ``grid_summary.png`` (each mapper's mean final GOSPA per point).
    Keyword arguments go to :func:`run_sweep`; every run's JSON line carries its ``grid_point``.

    Raises:
        SweepError: as :func:`run_sweep`, a grid key also given with ``--set``, or a grid
            point the scenario refuses (named with its ``--grid`` values).
        OutputDirError: ``out`` is protected, holds something else, or is a plain sweep.
    """
    both = sorted(set(grid) & set(spec.overrides))
    if both:
        raise SweepError(f"--grid {both[0]}: also given with --set; give it in one place")
    points = grid_points(grid)
    for point in points:  # every point is checked before any runs
        try:
            sweep_parts(spec.scenario)[0](SweepSpec(spec.scenario, spec.runs, spec.seed, {**spec.overrides, **point}))
        except SweepError as exc:
            raise SweepError(f"--grid: {exc}") from None
    folder = _check_sweep_folder(out, GRID_KIND)
    folder.mkdir(parents=True, exist_ok=True)
    write_marker(folder, GRID_KIND)
    emit = kwargs.pop("emit", None) or (lambda line: print(line, flush=True))
    rows = []
    for n, point in enumerate(points, 1):
        sub = SweepSpec(spec.scenario, spec.runs, spec.seed, {**spec.overrides, **point})
        tag = json.dumps(point)

        def emit_point(line: str, tag: str = tag) -> None:
            emit(line[:-1] + f', "grid_point": {tag}}}' if line.endswith("}") else line)

        label = f"sweep, grid point {n}/{len(points)} ({', '.join(f'{k}={json.dumps(v)}' for k, v in point.items())})"
        summary = run_sweep(folder / point_folder_name(point), sub, emit=emit_point, label=label, **kwargs)
        rows.append({"point": point, "folder": point_folder_name(point), "summary": summary})
    _write_atomic(folder / "grid_summary.json", json.dumps({"grid": grid, "points": rows}, indent=1))

    write_grid_figure(folder / "grid_summary.png", spec.scenario, rows, spec.runs)
    return {"runs": spec.runs * len(points), "points": rows}


def _check_sweep_folder(out: str | os.PathLike[str], kind: str) -> Path:
    """:func:`check_output_dir` for a sweep (``kind`` :data:`SWEEP_KIND`) or a grid
    (:data:`GRID_KIND`) folder, refusing the other kind by name."""
    path = Path(os.fspath(out)).expanduser()
    if path.is_dir() and _is_grid_folder(path) != (kind == GRID_KIND) and (
            is_output_of(path, SWEEP_KIND) or is_output_of(path, GRID_KIND)):
        if kind == GRID_KIND:
            raise OutputDirError(f"--out {out}: holds a sweep without --grid; a grid needs a folder of its own "
                                 "(name a new folder)")
        raise OutputDirError(f"--out {out}: holds a --grid sweep; resume it with the same --grid arguments, "
                             "or name a new folder")
    legacy_grid = kind == GRID_KIND and path.is_dir() and is_output_of(path, SWEEP_KIND)
    return check_output_dir(out, kind=SWEEP_KIND if legacy_grid else kind, resume=True)


def _mcm_config(spec: SweepSpec):
    from pydantic import ValidationError

    from sim.mcm.survey import McmSurveyConfig

    known = ", ".join(McmSurveyConfig.model_fields)
    data = {"seed": spec.seed}
    for key, value in spec.overrides.items():
        if key not in McmSurveyConfig.model_fields:
            raise SweepError(f"mcm_survey: {key}: unknown key; mcm_survey's keys (flat, no dots) are: {known}")
        data[key] = value
    try:
        return McmSurveyConfig(**data)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(x) for x in err["loc"][:1])
        if where:
            given = spec.overrides.get(where, data.get(where))
            raise SweepError(f"mcm_survey: {where}={json.dumps(given)}: {err['msg']}") from None
        raise SweepError(f"mcm_survey: {err['msg'].removeprefix('Value error, ')}") from None


def _mcm_job(args: tuple[dict, int]) -> dict:
    from sim.mcm.survey import McmSurveyConfig, run_survey

    cfg_json, i = args
    return run_survey(McmSurveyConfig(**cfg_json), i)


def _mcm_finish(out: Path, spec: SweepSpec, results: list[dict]) -> dict:
    summary = summarise(results)
    write_figures(out, results, scenario=spec.scenario)
    return summary


def _mcm_full_config(spec: SweepSpec):
    """A scenario file with ``mcm.mode: full``; ``--set`` keys are the scenario's dotted keys."""
    from scenarios.load import ScenarioError, load_scenario, resolve_path

    try:
        resolve_path(spec.scenario)
    except ScenarioError:
        names = sweepable_names()
        close = difflib.get_close_matches(spec.scenario, names, n=1)
        hint = f"; did you mean {close[0]}?" if close else ""
        raise SweepError(f"{spec.scenario}: no such sweepable scenario{hint} (sweepable: {', '.join(names)}, "
                         "or a scenario file with mcm.mode: full)") from None
    items = [f"{k}={json.dumps(v)}" for k, v in spec.overrides.items()] + [f"seed={spec.seed}"]
    try:
        scenario = load_scenario(spec.scenario, items)
    except ScenarioError as exc:
        hint = _dotted_key_hint(spec)
        raise SweepError(str(exc).splitlines()[0] + hint if hint else str(exc)) from None
    if scenario.mcm.mode != "full":
        raise SweepError(f"{spec.scenario}: has no Monte Carlo runner (mcm.mode is {scenario.mcm.mode!r}; "
                         f"sweepable: {', '.join(sweepable_names())}, or a scenario file with mcm.mode: full)")
    return scenario


def _dotted_key_hint(spec: SweepSpec) -> str:
    """For flat ``--set`` keys (``n_particles``, as ``mcm_survey`` takes them) on a scenario
    file: ``; did you mean mcm.mapper.n_particles?`` naming the scenario's dotted keys of
    that leaf name under ``mcm`` (empty when there are none)."""
    from scenarios.load import ScenarioError, load_scenario

    flat = [k for k in spec.overrides if "." not in k]
    if not flat:
        return ""
    try:
        base = load_scenario(spec.scenario).model_dump(mode="json")
    except ScenarioError:
        return ""

    def leaves(node: Any, prefix: str) -> Iterator[str]:
        if isinstance(node, dict):
            for k, v in node.items():
                yield from leaves(v, f"{prefix}.{k}")
        else:
            yield prefix

    found = [path for path in leaves(base.get("mcm", {}), "mcm") for k in flat if path.endswith(f".{k}")]
    return f"; did you mean {' or '.join(found)}?" if found else ""


def sweepable_names() -> list[str]:
    """The names ``auvsim sweep`` takes: :data:`SWEEPABLE` and the shipped scenarios with
    ``mcm.mode: full``."""
    from scenarios.load import scenarios_dir

    names = list(SWEEPABLE)
    for path in sorted(scenarios_dir().glob("*.yaml")):
        try:
            data = yaml.safe_load(path.read_text()) or {}
        except yaml.YAMLError:
            continue
        mcm = data.get("mcm") if isinstance(data, dict) else None
        if isinstance(mcm, dict) and mcm.get("mode") == "full":
            names.append(path.stem)
    return names


def _mcm_full_job(args: tuple[dict, int]) -> dict:
    from scenarios.schema import Scenario

    scenario_json, i = args
    return run_full(Scenario.model_validate(scenario_json), i)


#: studies that run only as sweeps (no scenario file) -> one-line description
SWEEP_ONLY: dict[str, str] = {
    "mcm_survey": "Paper 003 MCM Monte Carlo study, kinematic mode (planned path, INS drift, detection-level "
                  "ATR; no MuJoCo) - SPA mapper against clairvoyant, INS-plain and INS-filter; runs only as "
                  "auvsim sweep mcm_survey --runs N --out DIR",
}
#: scenario name -> (config builder, run job (picklable), finisher (summary + figures))
SWEEPABLE: dict[str, tuple[Callable, Callable, Callable]] = {"mcm_survey": (_mcm_config, _mcm_job, _mcm_finish)}
#: any other scenario with ``mcm.mode: full`` sweeps with these
MCM_FULL = (_mcm_full_config, _mcm_full_job, _mcm_finish)


def sweep_parts(scenario: str) -> tuple[Callable, Callable, Callable]:
    """The (config builder, job, finisher) of ``scenario``: :data:`SWEEPABLE`, else the full
    MCM mode for a scenario file (checked by the builder)."""
    return SWEEPABLE.get(scenario, MCM_FULL)


def _write_atomic(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    tmp.write_text(text)
    os.replace(tmp, path)


def probe_ray_address(address: str, timeout_s: float = 3.0) -> None:
    """Fail fast when a Ray head does not answer at ``host:port`` (``ray://host:port``);
    ``auto`` and addresses without a port are left to Ray.

    Raises:
        SweepError: nothing accepts a TCP connection there within ``timeout_s``.
    """
    import socket

    hostport = address.split("://", 1)[-1]
    host, sep, port = hostport.rpartition(":")
    if not sep or not port.isdigit() or address == "auto":
        return
    try:
        socket.create_connection((host or "127.0.0.1", int(port)), timeout=timeout_s).close()
    except OSError as exc:
        raise SweepError(f"--ray {address}: no Ray cluster answers there ({exc.strerror or exc}); "
                         "start one with `ray start --head` or omit the address for a local instance") from None


def _connect_ray(address: str | None):
    try:
        import ray
    except ImportError as exc:
        raise SweepError(RAY_HINT) from exc
    if ray.is_initialized():
        return ray, False
    try:
        ray.init(address=address, include_dashboard=False, log_to_driver=False, ignore_reinit_error=True)
    except Exception as exc:  # noqa: BLE001 - Ray raises many types for an address that does not answer
        raise SweepError(f"--ray {address or ''}: cannot connect to Ray ({exc.__class__.__name__}: "
                         f"{str(exc).splitlines()[0] if str(exc) else 'no answer'})") from None
    return ray, True


def pool_worker_init() -> None:
    """A pool worker's set-up. Ctrl-C is the parent's to handle (it stops the pool and says
    what is kept; a worker would print a traceback of its own), and tqdm (the mission loop's
    progress bar, disabled in a sweep) takes a thread lock, not its default cross-process
    semaphore, which a stopped worker would leave behind (a ``leaked semaphore`` warning)."""
    import signal
    import threading

    from tqdm import tqdm

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    tqdm.set_lock(threading.RLock())


def run_jobs(job: Callable, args: list[tuple], workers: int = 1, use_ray: bool = False, address: str | None = None
             ) -> Iterator[dict]:
    """``job(a)`` for each of ``args``, yielded as they finish: in this process (one worker),
    in ``workers`` spawned processes (:func:`pool_worker_init`; leaving early, Ctrl-C
    included, stops them at once) or on Ray (a local instance, or the cluster at ``address``).

    Raises:
        SweepError: Ray missing or unreachable.
    """
    if not args:  # a finished sweep resumed: nothing to start
        return
    if use_ray:
        ray, started = _connect_ray(address)
        try:
            remote = ray.remote(job)
            pending = [remote.remote(a) for a in args]
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                yield ray.get(done[0])
        finally:
            if started:
                ray.shutdown()
    elif workers <= 1 or len(args) <= 1:
        for a in args:
            yield job(a)
    else:
        import multiprocessing as mp

        with mp.get_context("spawn").Pool(min(workers, len(args)), initializer=pool_worker_init) as pool:
            yield from pool.imap_unordered(job, args)
            # let the workers exit on their own (leaving the block terminates them), so what
            # they hold is released and not reported as leaked at shutdown
            pool.close()
            pool.join()


def _is_grid_folder(path: Path) -> bool:
    """A ``--grid`` sweep's folder: marked so, or (older folders, marked ``sweep``) holding
    sub-sweeps but no ``sweep.json`` of its own."""
    if is_output_of(path, GRID_KIND):
        return True
    return (is_output_of(path, SWEEP_KIND) and not (path / "sweep.json").exists()
            and any((child / "sweep.json").is_file() for child in path.iterdir()))


def _scalars(value: Any) -> Any:
    """``value`` without its lists (a run's per-tile curves): what a console line carries."""
    if isinstance(value, dict):
        return {k: _scalars(v) for k, v in value.items() if not isinstance(v, list)}
    return value


def run_sweep(out: str | os.PathLike[str], spec: SweepSpec, *, workers: int = 1, use_ray: bool = False,
              ray_address: str | None = None, progress: bool = True, emit: Callable[[str], None] | None = None,
              label: str = "sweep") -> dict:
    """Run (or resume) a sweep into ``out``; returns the summary.

    A folder holding fewer runs of the same spec is extended to ``spec.runs`` (run ``i`` is
    seed ``seed + i`` whatever the count); fewer runs than it holds are refused.

    Args:
        out: the sweep folder (new, or an earlier sweep of the same spec to resume or extend).
        spec: what to run.
        workers: local processes when not on Ray.
        use_ray, ray_address: run on Ray (``None`` address: a local instance).
        progress: progress lines on stderr, prefixed with ``label``.
        emit: called with one JSON line per finished run: its scalar results, without the
            per-tile curves that ``runs/run_NNNNN.json`` holds (default: print to stdout).
        label: the progress lines' prefix.

    Raises:
        SweepError: unknown scenario, bad overrides, Ray unreachable.
        OutputDirError: the folder is protected, holds something else (a grid sweep
            included), a sweep of another spec, or more runs than ``spec.runs``.
    """
    build, job, finish = sweep_parts(spec.scenario)
    cfg = build(spec)
    folder = _check_sweep_folder(out, SWEEP_KIND)
    if use_ray and ray_address:
        probe_ray_address(ray_address)
    runs_dir = folder / "runs"
    spec_path = folder / "sweep.json"
    if spec_path.exists() and any(runs_dir.glob("run_*.json")):  # no finished run: new arguments are fine
        old = json.loads(spec_path.read_text())
        if {**old, "runs": spec.runs} != spec.as_json():
            raise OutputDirError(f"--out {out}: holds a sweep of other arguments ({_describe(old)}); resume it "
                                 "with those, or name a new folder")
        if old.get("runs", 0) > spec.runs:
            raise OutputDirError(f"--out {out}: holds a sweep of --runs {old['runs']}; resume or extend it with "
                                 f"--runs {old['runs']} or more, or name a new folder")
    runs_dir.mkdir(parents=True, exist_ok=True)
    write_marker(folder, SWEEP_KIND)
    _write_atomic(spec_path, json.dumps(spec.as_json(), indent=1))
    emit = emit or (lambda line: print(line, flush=True))
    todo = [i for i in range(spec.runs) if not (runs_dir / f"run_{i:05d}.json").exists()]
    done_before = spec.runs - len(todo)
    if progress and done_before:
        print(f"{label}: {done_before} of {spec.runs} runs already in {out}, {len(todo)} to run", file=sys.stderr,
              flush=True)
    t0 = time.perf_counter()
    cfg_json = cfg.model_dump(mode="json")
    n_done = 0
    try:
        for n_done, res in enumerate(run_jobs(job, [(cfg_json, i) for i in todo], workers, use_ray, ray_address), 1):
            _write_atomic(runs_dir / f"run_{int(res['run']):05d}.json", json.dumps(res))
            emit(json.dumps(_scalars(res)))
            if progress:
                el = time.perf_counter() - t0
                eta = el / n_done * (len(todo) - n_done)
                print(f"{label}: {done_before + n_done}/{spec.runs} runs ({el:.0f} s, ETA {eta:.0f} s)",
                      file=sys.stderr, flush=True)
    except BaseException as exc:  # Ctrl-C, SIGTERM or a failed run: say what is kept
        resumes = " (the same command resumes)" if not isinstance(exc, Exception) else ""
        print(f"{label}: stopped; {done_before + n_done} of {spec.runs} runs are kept in {out}{resumes}",
              file=sys.stderr, flush=True)
        raise
    results = [json.loads((runs_dir / f"run_{i:05d}.json").read_text()) for i in range(spec.runs)]
    _write_atomic(folder / "results.jsonl", "".join(json.dumps(r) + "\n" for r in results))
    summary = finish(folder, spec, results)
    summary["wall_s_this_call"] = time.perf_counter() - t0
    _write_atomic(folder / "summary.json", json.dumps(summary, indent=1))
    return summary


def _describe(spec_json: dict) -> str:
    """A sweep's arguments as a command line: ``mcm_survey --runs 3 --seed 0 --set n_particles=50``."""
    sets = "".join(f" --set {k}={json.dumps(v)}" for k, v in (spec_json.get("overrides") or {}).items())
    return f"{spec_json.get('scenario')} --runs {spec_json.get('runs')} --seed {spec_json.get('seed')}{sets}"


def run_full(scenario: Scenario, run_index: int = 0, *, progress: bool = False) -> dict:
    """One full-mode run of ``scenario`` at seed ``scenario.seed + run_index`` (headless; the
    sweep's job). Returns :meth:`sim.mcm.full_mode.McmFullObserver.results` with ``wall_s``."""
    import time

    from sim.mcm.full_mode import McmFullObserver
    from sim.mission import Mission

    seed = int(scenario.seed) + int(run_index)
    obs = McmFullObserver(scenario)
    t0 = time.perf_counter()
    mission = Mission(scenario.model_copy(update={"seed": seed}), observers=[obs])
    mission.reset()
    try:
        mission.run(progress=progress)
    finally:
        mission.close()
    out = obs.results(seed, run_index)
    out["wall_s"] = time.perf_counter() - t0
    return out
