"""The tasks' time limit, in decisions: one predicate for the gymnasium envs' ``truncated``
and the dm_control environments' step limit (:mod:`sim.envs.dm`), so both end an episode
at the same decision."""

from __future__ import annotations

import math

#: A decision clock within this of the time limit has reached it, s.
TIME_LIMIT_TOL_S = 1e-9


def reached_time_limit(n_steps: int, interval_s: float, limit_s: float) -> bool:
    """True once ``n_steps`` decisions of ``interval_s`` (s) reach ``limit_s`` (s): the
    episode clock ``n_steps * interval_s`` is at least ``limit_s - TIME_LIMIT_TOL_S``."""
    return n_steps * interval_s >= limit_s - TIME_LIMIT_TOL_S


def time_limit_steps(interval_s: float, limit_s: float) -> int:
    """The decision (1-based count, >= 1) at which :func:`reached_time_limit` first holds.

    Raises:
        ValueError: a non-positive or non-finite interval or limit.
    """
    if not (math.isfinite(interval_s) and interval_s > 0.0 and math.isfinite(limit_s) and limit_s > 0.0):
        raise ValueError(f"time_limit_steps needs a finite interval and limit > 0, got {interval_s}, {limit_s}")
    n = max(1, math.ceil((limit_s - TIME_LIMIT_TOL_S) / interval_s) - 1)
    while not reached_time_limit(n, interval_s, limit_s):
        n += 1
    while n > 1 and reached_time_limit(n - 1, interval_s, limit_s):
        n -= 1
    return n
