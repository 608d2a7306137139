"""Objects holding large numpy arrays passed between processes through shared memory.

A :class:`FrameRing` is a ring of fixed-size slots in one ``multiprocessing.shared_memory``
block, with one writer process and one reader process consuming the slots in the order they
were written. :meth:`FrameRing.put` pickles an object with its large C-contiguous arrays
copied into the next free slot (out of band, referenced from the pickle by offset) and sends
the small pickle over a ``multiprocessing`` connection; :meth:`FrameRing.get` rebuilds the
object with copies of the arrays and frees the slot. Objects both sides already hold (a
sensor's fixed tables: its fan geometry, its remap) travel as references to the receiver's
own copy (``shared``: name -> object, the same names on both sides). An object whose arrays do
not fit a slot travels in band, slower but whole.
"""

from __future__ import annotations

import io
import multiprocessing as mp
import pickle
from multiprocessing.shared_memory import SharedMemory
from typing import Any

import numpy as np

OUT_OF_BAND_MIN_BYTES = 32 * 1024  # smaller arrays stay in the pickle
PARENT_CHECK_S = 1.0  # a writer waiting for a free slot checks its parent this often


class _Pickler(pickle.Pickler):
    def __init__(self, file, ring: "FrameRing", slot: int, shared_ids: dict[int, str]) -> None:
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self.ring, self.slot, self.shared_ids, self.used = ring, slot, shared_ids, 0

    def persistent_id(self, obj: Any) -> Any:
        name = self.shared_ids.get(id(obj))
        if name is not None:
            return ("shared", name)
        if type(obj) is np.ndarray and obj.nbytes >= OUT_OF_BAND_MIN_BYTES and obj.flags.c_contiguous \
                and not obj.dtype.hasobject and self.used + obj.nbytes <= self.ring.slot_bytes:
            offset = self.slot * self.ring.slot_bytes + self.used
            self.ring.view(offset, obj.dtype, obj.shape)[...] = obj
            self.used += -(-obj.nbytes // 64) * 64  # next array 64-byte aligned
            return ("array", offset, obj.dtype.str, obj.shape)
        return None


class _Unpickler(pickle.Unpickler):
    def __init__(self, file, ring: "FrameRing", shared: dict[str, Any]) -> None:
        super().__init__(file)
        self.ring, self.shared = ring, shared

    def persistent_load(self, pid: Any) -> Any:
        if pid[0] == "shared":
            return self.shared[pid[1]]
        _, offset, dtype, shape = pid
        return self.ring.view(offset, np.dtype(dtype), shape).copy()


class FrameRing:
    """``slots`` shared-memory slots of ``slot_bytes`` each, written and read in turn.

    Create it in the parent (owner), pass it to the two processes at their start (it pickles
    as its block's name and its semaphore), :meth:`close` it everywhere and :meth:`unlink` it
    in the owner.

    Args:
        ctx: the ``multiprocessing`` context of the processes (for the slot semaphore).
        slots: slots in the ring (the writer waits while all hold unread objects), >= 1.
        slot_bytes: bytes per slot for out-of-band arrays, >= 64.

    Raises:
        ValueError: ``slots`` or ``slot_bytes`` out of range.
    """

    def __init__(self, ctx: Any, slots: int, slot_bytes: int) -> None:
        if slots < 1 or slot_bytes < 64:
            raise ValueError(f"FrameRing needs slots >= 1 and slot_bytes >= 64, got {slots}, {slot_bytes}")
        self.slots, self.slot_bytes = int(slots), -(-int(slot_bytes) // 64) * 64
        self._shm = SharedMemory(create=True, size=self.slots * self.slot_bytes)
        self._owner = True
        self._free = ctx.Semaphore(self.slots)
        self._next_put = 0

    def __getstate__(self) -> dict[str, Any]:
        return {"name": self._shm.name, "slots": self.slots, "slot_bytes": self.slot_bytes, "free": self._free}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.slots, self.slot_bytes, self._free = state["slots"], state["slot_bytes"], state["free"]
        self._shm = SharedMemory(name=state["name"])
        self._owner = False
        self._next_put = 0

    def view(self, offset: int, dtype: np.dtype, shape: tuple[int, ...]) -> np.ndarray:
        """An array over the block at byte ``offset`` (no copy)."""
        return np.ndarray(shape, dtype=dtype, buffer=self._shm.buf, offset=offset)

    def put(self, conn: Any, obj: Any, shared_ids: dict[int, str] | None = None) -> None:
        """Send ``obj`` over ``conn``, its large arrays through the next slot (waits for a free
        one); ``shared_ids``: ``id(object) -> name`` of the objects sent by reference.

        Raises:
            EOFError: this process's parent ended while it waited for a slot (the reader will
                never free one; a worker must not outlive the mission process).
        """
        parent = mp.parent_process()
        while not self._free.acquire(timeout=PARENT_CHECK_S):
            if parent is not None and not parent.is_alive():
                raise EOFError("the parent process ended while this one waited for a free slot")
        buf = io.BytesIO()
        _Pickler(buf, self, self._next_put, shared_ids or {}).dump(obj)
        self._next_put = (self._next_put + 1) % self.slots
        conn.send_bytes(buf.getbuffer())

    def get(self, conn: Any, shared: dict[str, Any] | None = None) -> Any:
        """The next object from ``conn`` (blocks until one comes); frees its slot.

        Raises:
            EOFError: the writer closed the connection.
        """
        data = conn.recv_bytes()
        try:
            return _Unpickler(io.BytesIO(data), self, shared or {}).load()
        finally:
            self._free.release()

    def close(self) -> None:
        """Detach from the block (every process)."""
        self._shm.close()

    def unlink(self) -> None:
        """Free the block (the owner, once every process closed or ended)."""
        if self._owner:
            self._shm.unlink()


def shared_objects(holder: Any) -> dict[str, Any]:
    """Name -> object of ``holder``'s attributes that are objects (not numbers, strings, arrays or
    generators): the fixed tables that messages may reference instead of carrying."""
    return {name: v for name, v in vars(holder).items()
            if v is not None and not isinstance(v, (bool, int, float, str, bytes, np.ndarray, np.generic,
                                                    np.random.Generator))}
