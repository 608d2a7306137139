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

import json
import os
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from sim.outputs.run_dir import OutputDirError, check_output_dir, write_marker

RAY_HINT = "--ray needs Ray: pip install 'auvsim[scale]' (or pip install ray)"
SWEEP_KIND = "sweep"


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
    overrides and summary. Keyword arguments go to :func:`run_sweep`; every run's JSON line
    carries its ``grid_point``.

    Raises:
        SweepError: as :func:`run_sweep`, or a grid key also given with ``--set``.
    """
    both = sorted(set(grid) & set(spec.overrides))
    if both:
        raise SweepError(f"--grid {both[0]}: also given with --set; give it in one place")
    points = grid_points(grid)
    for point in points:  # every point is checked before any runs
        sweep_parts(spec.scenario)[0](SweepSpec(spec.scenario, spec.runs, spec.seed, {**spec.overrides, **point}))
    folder = check_output_dir(out, kind=SWEEP_KIND, resume=True)
    folder.mkdir(parents=True, exist_ok=True)
    write_marker(folder, SWEEP_KIND)
    emit = kwargs.pop("emit", None) or (lambda line: print(line, flush=True))
    rows = []
    for point in points:
        sub = SweepSpec(spec.scenario, spec.runs, spec.seed, {**spec.overrides, **point})
        tag = json.dumps(point)

        def emit_point(line: str, tag: str = tag) -> None:
            emit(line[:-1] + f', "grid_point": {tag}}}' if line.endswith("}") else line)

        summary = run_sweep(folder / point_folder_name(point), sub, emit=emit_point, **kwargs)
        rows.append({"point": point, "folder": point_folder_name(point), "summary": summary})
    _write_atomic(folder / "grid_summary.json", json.dumps({"grid": grid, "points": rows}, indent=1))
    return {"runs": spec.runs * len(points), "points": rows}


def _mcm_config(spec: SweepSpec):
    from pydantic import ValidationError

    from sim.mcm.survey import McmSurveyConfig

    data = {"seed": spec.seed}
    for key, value in spec.overrides.items():
        if "." in key:
            raise SweepError(f"--set {key}: mcm_survey keys are flat (see McmSurveyConfig)")
        data[key] = value
    try:
        return McmSurveyConfig(**data)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(x) for x in err["loc"]) or "mcm_survey"
        raise SweepError(f"mcm_survey: {where}: {err['msg']}") from None


def _mcm_job(args: tuple[dict, int]) -> dict:
    from sim.mcm.survey import McmSurveyConfig, run_survey

    cfg_json, i = args
    return run_survey(McmSurveyConfig(**cfg_json), i)


def _mcm_finish(out: Path, spec: SweepSpec, results: list[dict]) -> dict:
    from sim.mcm.figures import summarise, write_figures

    summary = summarise(results)
    write_figures(out, results)
    return summary


def _mcm_full_config(spec: SweepSpec):
    """A scenario file with ``mcm.mode: full``; ``--set`` keys are the scenario's dotted keys."""
    from scenarios.load import ScenarioError, load_scenario

    items = [f"{k}={json.dumps(v)}" for k, v in spec.overrides.items()] + [f"seed={spec.seed}"]
    try:
        scenario = load_scenario(spec.scenario, items)
    except ScenarioError as exc:
        raise SweepError(f"sweep: {exc} (sweepable: mcm_survey and scenarios with mcm.mode: full)") from None
    if scenario.mcm.mode != "full":
        raise SweepError(f"sweep: scenario {spec.scenario!r} has no Monte Carlo runner (mcm.mode is "
                         f"{scenario.mcm.mode!r}; sweepable: mcm_survey and scenarios with mcm.mode: full)")
    return scenario


def _mcm_full_job(args: tuple[dict, int]) -> dict:
    from scenarios.schema import Scenario
    from sim.mcm.full_mode import run_full

    scenario_json, i = args
    return run_full(Scenario.model_validate(scenario_json), i)


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


def _execute(job: Callable, args: list[tuple], workers: int, use_ray: bool, address: str | None
             ) -> Iterator[dict]:
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
    elif workers <= 1:
        for a in args:
            yield job(a)
    else:
        import multiprocessing as mp

        with mp.get_context("spawn").Pool(min(workers, len(args))) as pool:
            yield from pool.imap_unordered(job, args)


def run_sweep(out: str | os.PathLike[str], spec: SweepSpec, *, workers: int = 1, use_ray: bool = False,
              ray_address: str | None = None, progress: bool = True, emit: Callable[[str], None] | None = None
              ) -> dict:
    """Run (or resume) a sweep into ``out``; returns the summary.

    Args:
        out: the sweep folder (new, or an earlier sweep of the same spec to resume).
        spec: what to run.
        workers: local processes when not on Ray.
        use_ray, ray_address: run on Ray (``None`` address: a local instance).
        progress: progress lines on stderr.
        emit: called with one JSON line per finished run (default: print to stdout).

    Raises:
        SweepError: unknown scenario, bad overrides, a resumed folder of another spec, Ray
            unreachable.
        OutputDirError: the folder is protected or holds something else.
    """
    build, job, finish = sweep_parts(spec.scenario)
    cfg = build(spec)
    folder = check_output_dir(out, kind=SWEEP_KIND, resume=True)
    if use_ray and ray_address:
        probe_ray_address(ray_address)
    runs_dir = folder / "runs"
    spec_path = folder / "sweep.json"
    if spec_path.exists():
        old = json.loads(spec_path.read_text())
        if old != spec.as_json():
            raise OutputDirError(f"--out {folder}: holds a sweep of other arguments ({old}); name a new folder")
    runs_dir.mkdir(parents=True, exist_ok=True)
    write_marker(folder, SWEEP_KIND)
    _write_atomic(spec_path, json.dumps(spec.as_json(), indent=1))
    emit = emit or (lambda line: print(line, flush=True))
    todo = [i for i in range(spec.runs) if not (runs_dir / f"run_{i:05d}.json").exists()]
    done_before = spec.runs - len(todo)
    t0 = time.perf_counter()
    cfg_json = cfg.model_dump(mode="json")
    for n_done, res in enumerate(_execute(job, [(cfg_json, i) for i in todo], workers, use_ray, ray_address), 1):
        line = json.dumps(res)
        _write_atomic(runs_dir / f"run_{int(res['run']):05d}.json", line)
        emit(line)
        if progress:
            el = time.perf_counter() - t0
            eta = el / n_done * (len(todo) - n_done)
            print(f"sweep: {done_before + n_done}/{spec.runs} runs ({el:.0f} s, ETA {eta:.0f} s)", file=sys.stderr,
                  flush=True)
    results = [json.loads((runs_dir / f"run_{i:05d}.json").read_text()) for i in range(spec.runs)]
    _write_atomic(folder / "results.jsonl", "".join(json.dumps(r) + "\n" for r in results))
    summary = finish(folder, spec, results)
    summary["wall_s_this_call"] = time.perf_counter() - t0
    _write_atomic(folder / "summary.json", json.dumps(summary, indent=1))
    return summary
