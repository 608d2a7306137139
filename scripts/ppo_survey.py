"""PPO on the batched Survey env: a learning-curve smoke test on the CPU (the ``train`` extra).

Stable-Baselines3's PPO ([Raffin2021], [Schulman2017]) with its multi-input policy trains on
:class:`sim.envs.sb3_vec.Sb3SurveyVecEnv` (N Survey envs in lockstep in the worker
processes), then the same number of episodes of the env's uniform random policy are run for
comparison. Prints one JSON object: per PPO rollout the env steps so far and the mean return
of the episodes that ended in it, the first and last rollouts' means, the random policy's mean
return, the training's wall time and CPU time (this process and the env workers); ``--out DIR`` writes it as ``ppo_survey.json`` with the learning
curve as ``ppo_survey.png``.

    python scripts/ppo_survey.py --n-envs 8 --timesteps 30000 --max-episode-s 60 --out runs/ppo
    python scripts/ppo_survey.py --sonar --n-envs 4 --timesteps 2000 --max-episode-s 30
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sim.cli.app import run_script, script_parser  # noqa: E402
from sim.cli.args import int_between, positive_float, positive_int  # noqa: E402
from sim.cli.errors import CliError  # noqa: E402

MAX_SEED = 2**32 - 1 - 10_000  # Stable-Baselines3 seeds numpy's legacy generator: below 2**32, per env seed + i
seed_int = int_between(0, MAX_SEED)


def main(argv: list[str] | None = None) -> int:
    """Parse ``argv`` and train; bad arguments: one line, exit status 2."""
    ap = script_parser("ppo_survey.py", __doc__.splitlines()[0])
    ap.add_argument("--scenario", default="cssn_lawnmower", help="scenario name or path (default cssn_lawnmower)")
    ap.add_argument("--n-envs", type=positive_int, default=8, help="envs in the batch (default 8)")
    ap.add_argument("--workers", type=positive_int, default=None, help="worker processes (default the cores, at most N)")
    ap.add_argument("--timesteps", type=positive_int, default=30000, help="env steps of training (default 30000)")
    ap.add_argument("--n-steps", type=positive_int, default=128, help="PPO rollout length per env (default 128)")
    ap.add_argument("--max-episode-s", type=positive_float, default=60.0, help="episode time limit, s (default 60)")
    ap.add_argument("--sonar", action="store_true", help="with the FLS, ATR, world model and the sonar image")
    ap.add_argument("--seed", type=seed_int, default=0, help=f"root seed, 0 to {MAX_SEED} (default 0)")
    ap.add_argument("--out", type=Path, default=None, help="folder for ppo_survey.json and ppo_survey.png")
    return run_script(ap, train, argv)




def train(args) -> int:
    """Train PPO and run the random baseline as :func:`main` parsed ``args`` ask."""
    try:
        import torch
        from stable_baselines3 import PPO
        from stable_baselines3.common.callbacks import BaseCallback
        from stable_baselines3.common.vec_env import VecMonitor
    except ImportError as e:
        raise CliError(f"needs the train extra (pip install 'auvsim[train]'): {e}") from None
    import numpy as np

    from sim.bench.gym import process_cpu_s
    from sim.envs.sb3_vec import Sb3SurveyVecEnv

    if args.out is not None:  # made now, so that a bad path costs no training
        if args.out.exists() and not args.out.is_dir():
            raise CliError(f"--out {args.out}: exists and is not a folder")
        try:
            args.out.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise CliError(f"--out {args.out}: cannot make the folder ({e.strerror})") from None
    workers = min(args.workers or os.cpu_count() or 1, args.n_envs)
    options = {"sonar": args.sonar, "max_episode_s": args.max_episode_s}
    torch.set_num_threads(1)
    torch.manual_seed(args.seed)
    try:
        env = VecMonitor(Sb3SurveyVecEnv(args.n_envs, args.scenario, options, workers=workers, seed=args.seed))
    except ValueError as e:  # the scenario cannot hold the Survey task (no FLS entry, an area too small)
        raise CliError(f"--scenario {args.scenario}: {e}") from None
    pids = [os.getpid()] + [p.pid for p in env.venv.venv._procs]

    class Curve(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.rows: list[dict] = []
            self.seen = 0

        def _on_step(self) -> bool:
            for info in self.locals.get("infos", []):
                ep = info.get("episode")
                if ep is not None:
                    self.current.append(float(ep["r"]))
            return True

        def _on_rollout_start(self) -> None:
            self.current: list[float] = []

        def _on_rollout_end(self) -> None:
            row = {"env_steps": int(self.num_timesteps), "episodes": len(self.current),
                   "mean_return": round(float(np.mean(self.current)), 4) if self.current else None}
            self.rows.append(row)
            print(f"ppo_survey: {row['env_steps']} env steps, {row['episodes']} episodes ended, mean return "
                  f"{row['mean_return']}", file=sys.stderr, flush=True)

    curve = Curve()
    t0, c0 = time.perf_counter(), sum(process_cpu_s(p) or 0.0 for p in pids)
    try:
        model = PPO("MultiInputPolicy", env, n_steps=args.n_steps, batch_size=min(256, args.n_steps * args.n_envs),
                    seed=args.seed, verbose=0, device="cpu")
        model.learn(total_timesteps=args.timesteps, callback=curve)
        train_wall = time.perf_counter() - t0
        cpu_s = sum(process_cpu_s(p) or 0.0 for p in pids) - c0
        # the random policy on the same envs, as many episodes as the first rollouts ended
        rng = np.random.default_rng(args.seed + 1)
        env.reset()
        random_returns: list[float] = []
        want = max(args.n_envs, 8)
        while len(random_returns) < want:
            _, _, _, infos = env.step(rng.uniform(-1, 1, (args.n_envs, 3)).astype(np.float32))
            random_returns += [float(i["episode"]["r"]) for i in infos if "episode" in i]
    finally:
        env.close()
    rows = [r for r in curve.rows if r["mean_return"] is not None]
    first, last = (rows[0], rows[-1]) if rows else (None, None)
    result = {"n_envs": args.n_envs, "workers": workers, "sonar": args.sonar, "max_episode_s": args.max_episode_s,
              "timesteps": args.timesteps, "curve": curve.rows,
              "first_rollout_mean_return": first and first["mean_return"],
              "last_rollout_mean_return": last and last["mean_return"],
              "random_policy_mean_return": float(np.mean(random_returns)), "random_episodes": len(random_returns),
              "train_wall_s": round(train_wall, 1), "train_cpu_s": round(cpu_s, 1)}
    if args.out is not None:
        (args.out / "ppo_survey.json").write_text(json.dumps(result, indent=1))
        _plot(result, args.out / "ppo_survey.png")
    print(json.dumps(result))
    return 0


def _plot(result: dict, path: Path) -> None:
    """The learning curve (mean return of the episodes ended in each rollout against env steps)
    with the random policy's mean, PNG at ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in result["curve"] if r["mean_return"] is not None]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot([r["env_steps"] for r in rows], [r["mean_return"] for r in rows], "o-", ms=3, label="PPO, per rollout")
    ax.axhline(result["random_policy_mean_return"], color="r", ls="--", lw=1,
               label=f"random policy ({result['random_episodes']} episodes)")
    ax.set_xlabel("env steps")
    ax.set_ylabel("mean episode return")
    ax.set_title(f"PPO on the batched Survey env: {result['n_envs']} envs, "
                 f"{'sonar' if result['sonar'] else 'no sonar'}, {result['max_episode_s']:g} s episodes", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())
