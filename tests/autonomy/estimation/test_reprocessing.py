"""The out-of-sequence re-processing history against a filter run on the events in time order
from the start (the oracle), for both checkpoint policies, with pruning and refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from autonomy.estimation.reprocessing import ReprocessingHistory
from autonomy.estimation.updater import kalman_update


class RandomWalkFilter:
    """A 1-D random-walk Kalman filter on (position, velocity) with position fixes: events are
    ``(t_s, z)`` (a fix) or ``(t_s, None)`` (a prediction to ``t_s``). Its state is changed in
    place, so the history must copy it."""

    def __init__(self) -> None:
        self.t_s = 0.0
        self.x = np.zeros(2)
        self.P = np.diag([4.0, 1.0])
        self.n_applied = 0

    def apply(self, event: tuple[float, float | None]) -> bool:
        self.n_applied += 1
        t_s, z = event
        dt = t_s - self.t_s
        if dt > 0.0:
            F = np.array([[1.0, dt], [0.0, 1.0]])
            Q = 0.05 * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
            self.x = F @ self.x
            self.P = F @ self.P @ F.T + Q
            self.t_s = t_s
        if z is None:
            return False
        self.x[:], self.P[:] = kalman_update(self.x, self.P, [z - self.x[0]], [[1.0, 0.0]], [[0.25]])
        return True

    def save(self):
        return self.t_s, self.x.copy(), self.P.copy()

    def restore(self, state) -> None:
        self.t_s, x, P = state
        self.x[:], self.P[:] = x, P


def _events(seed: int, n: int = 60):
    rng = np.random.default_rng(seed)
    times = np.cumsum(rng.uniform(0.05, 0.6, n))
    return [(float(t), float(np.sin(0.3 * t) + rng.normal(0, 0.5)) if rng.random() < 0.5 else None) for t in times]


def _oracle(events):
    f = RandomWalkFilter()
    for ev in sorted(events, key=lambda e: e[0]):
        f.apply(ev)
    return f


@pytest.mark.parametrize("every_s", [None, 0.7, 3.0])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_late_events_give_the_in_order_filter(seed, every_s):
    events = _events(seed)
    rng = np.random.default_rng(100 + seed)
    late = set(rng.choice(len(events), size=15, replace=False).tolist())
    f = RandomWalkFilter()
    h = ReprocessingHistory(f.apply, f.save, f.restore, lambda: f.t_s, checkpoint_every_s=every_s)
    delayed = []
    for i, ev in enumerate(events):
        if i in late:
            delayed.append(ev)
            continue
        h.append(ev)
        # deliver a late event some time after it was made, out of order among themselves
        if delayed and rng.random() < 0.4:
            d = delayed.pop(int(rng.integers(len(delayed))))
            out = h.insert(d, d[0])
            assert out == (d[1] is not None)
    for d in delayed:
        h.insert(d, d[0])
    ref = _oracle(events)
    # the same sequence of floating-point operations: equal bit for bit
    assert f.t_s == ref.t_s
    np.testing.assert_array_equal(f.x, ref.x)
    np.testing.assert_array_equal(f.P, ref.P)
    assert [e[0] for e in h.events] == sorted(e[0] for e in events)


def test_checkpoint_cadence_bounds_the_replay():
    events = _events(3, n=200)
    costs = {}
    for every_s in (None, 5.0):
        f = RandomWalkFilter()
        h = ReprocessingHistory(f.apply, f.save, f.restore, lambda: f.t_s, checkpoint_every_s=every_s)
        for ev in events[:-1]:
            h.append(ev)
        before = f.n_applied
        t_late = events[-2][0] - 0.01  # just before the newest event applied
        h.insert((t_late, 0.0), t_late)
        costs[every_s] = f.n_applied - before
    assert costs[None] == 2  # the late event and the one after it
    # at most one checkpoint period of events (mean spacing 0.325 s) plus the two
    assert 2 <= costs[5.0] <= 2 + math.ceil(5.0 / 0.05)


def test_pruning_refuses_older_events_and_keeps_the_rest_exact():
    events = _events(4, n=100)
    f = RandomWalkFilter()
    h = ReprocessingHistory(f.apply, f.save, f.restore, lambda: f.t_s, checkpoint_every_s=1.0, keep_s=5.0)
    for ev in events[:80]:
        h.append(ev)
    t_oldest, _ = h.oldest
    assert f.t_s - 5.0 - 1.0 - 1e-9 <= t_oldest <= f.t_s - 5.0 + 1e-9
    with pytest.raises(ValueError, match="older than the kept history"):
        h.insert((t_oldest - 0.1, 1.0), t_oldest - 0.1)
    # a late event inside the kept history: the filter equals the in-order one
    late = (f.t_s - 2.0, 0.7)
    h.insert(late, late[0])
    for ev in events[80:]:
        h.append(ev)
    ref = _oracle(events + [late])
    np.testing.assert_array_equal(f.x, ref.x)
    np.testing.assert_array_equal(f.P, ref.P)


def test_caller_pruning_with_a_checkpoint_per_event():
    events = _events(5, n=50)
    f = RandomWalkFilter()
    h = ReprocessingHistory(f.apply, f.save, f.restore, lambda: f.t_s)
    for ev in events:
        h.append(ev)
    cut = events[20][0]
    h.prune(cut)
    assert h.events[0][0] == cut  # the events before it folded into the oldest state
    assert h.oldest[0] == events[19][0]


def test_apply_sees_the_event_in_the_history():
    seen = []
    state = {"t": -math.inf}

    def apply(ev):
        seen.append(list(h.events))
        state["t"] = ev

    h = ReprocessingHistory(apply, lambda: state["t"], lambda s: state.update(t=s), lambda: state["t"])
    h.append(1.0)
    h.append(3.0)
    h.insert(2.0, 2.0)
    assert seen[-2] == [1.0, 2.0] and seen[-1] == [1.0, 2.0, 3.0]


def test_bad_arguments_are_refused():
    f = RandomWalkFilter()
    with pytest.raises(ValueError, match="checkpoint_every_s"):
        ReprocessingHistory(f.apply, f.save, f.restore, lambda: f.t_s, checkpoint_every_s=0.0)
    with pytest.raises(ValueError, match="keep_s"):
        ReprocessingHistory(f.apply, f.save, f.restore, lambda: f.t_s, keep_s=-1.0)
    h = ReprocessingHistory(f.apply, f.save, f.restore, lambda: f.t_s)
    with pytest.raises(ValueError, match="finite"):
        h.insert((1.0, None), math.nan)
