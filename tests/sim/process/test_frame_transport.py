"""Shared-memory frame ring: arrays out of band and back equal, shared tables by reference,
too-large arrays in band, slots reused in turn."""

from __future__ import annotations

import multiprocessing as mp
import threading
from dataclasses import dataclass

import numpy as np
import pytest

from sim.process.frame_transport import OUT_OF_BAND_MIN_BYTES, FrameRing, shared_objects


@dataclass
class _Holder:
    table: dict
    lut: np.ndarray
    rate_hz: float


@pytest.fixture
def ring():
    r = FrameRing(mp.get_context("spawn"), slots=2, slot_bytes=1 << 20)
    yield r
    r.close()
    r.unlink()


def test_arrays_come_back_equal_and_shared_tables_by_reference(ring):
    rng = np.random.default_rng(3)
    big = rng.random((300, 200)).astype(np.float32)  # 240 kB: out of band
    small = np.arange(5)
    ints = rng.integers(0, 255, (700, 900), dtype=np.uint8)
    sender, receiver = _Holder({"a": 1}, np.ones(3), 2.0), _Holder({"a": 1}, np.ones(3), 2.0)
    r, w = mp.Pipe(duplex=False)
    msg = {"big": big, "small": small, "ints": ints, "t_s": 1.5, "table": sender.table}
    ring.put(w, msg, {id(v): k for k, v in shared_objects(sender).items()})
    wire = r.poll() and len(r.recv_bytes())  # the pickle alone crossed the pipe
    assert wire < OUT_OF_BAND_MIN_BYTES
    for _ in range(3):  # the slots are reused in turn
        ring.put(w, msg, {id(v): k for k, v in shared_objects(sender).items()})
        got = ring.get(r, shared_objects(receiver))
        assert got["big"].dtype == np.float32 and np.array_equal(got["big"], big)
        assert np.array_equal(got["ints"], ints) and np.array_equal(got["small"], small) and got["t_s"] == 1.5
        assert got["table"] is receiver.table  # the receiver's own copy, not a new one
    assert set(shared_objects(sender)) == {"table"}  # arrays and numbers are never shared


def test_an_array_larger_than_a_slot_travels_in_band(ring):
    huge = np.arange(400_000, dtype=np.float64)  # 3.2 MB > 1 MiB slot
    r, w = mp.Pipe(duplex=False)
    got = []
    reader = threading.Thread(target=lambda: got.append(ring.get(r)))  # the pipe holds less than the pickle
    reader.start()
    ring.put(w, huge)
    reader.join(60)
    assert np.array_equal(got[0], huge)


def test_bad_ring_sizes_are_refused():
    with pytest.raises(ValueError, match="slots"):
        FrameRing(mp.get_context("spawn"), slots=0, slot_bytes=1024)
