"""A process's memory of results it computed, bounded in bytes: a fit simulates the same records at the same
parameters many times over (every fit starts from the model it extends, a least-squares run re-evaluates its
start, a continuation stage the point the stage before it ended at, a channel delay changes no simulation)."""
from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

import numpy as np


def digest(*parts) -> str:
    """A key for values that define a computation: numbers (by their exact bits: -0.0 is not 0.0), strings,
    arrays (dtype, shape and bytes), and dicts, lists and tuples of these (dicts by their items in order)."""
    h = hashlib.blake2b(digest_size=20)

    def add(x):
        if isinstance(x, np.ndarray):
            a = np.ascontiguousarray(x)
            h.update(f"a{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
        elif isinstance(x, dict):
            h.update(b"d")
            for k, v in x.items():
                add(k)
                add(v)
        elif isinstance(x, (list, tuple)):
            h.update(f"l{len(x)}".encode())
            for v in x:
                add(v)
        elif isinstance(x, (bool, int, float, np.number)) or x is None:
            h.update(b"n" + (b"None" if x is None else float(x).hex().encode()))
        else:
            h.update(b"s" + str(x).encode())
        h.update(b"|")

    for p in parts:
        add(p)
    return h.hexdigest()


class BoundedMemo:
    """Values by key, the least recently used ones forgotten once their arrays' bytes exceed `max_bytes`;
    safe to share between threads. The values are shared between the callers: read them only."""

    def __init__(self, max_bytes: int):
        self.max_bytes = max_bytes
        self._items: OrderedDict = OrderedDict()  # key -> (value, bytes)
        self._bytes = 0
        self._lock = threading.Lock()

    def get(self, key):
        """The value remembered under key, or None."""
        with self._lock:
            item = self._items.get(key)
            if item is None:
                return None
            self._items.move_to_end(key)
            return item[0]

    def put(self, key, value, nbytes: int) -> None:
        """Remember value (whose arrays hold nbytes) under key; a value larger than the whole memory is not kept."""
        if nbytes > self.max_bytes:
            return
        with self._lock:
            if key in self._items:
                return
            self._items[key] = (value, nbytes)
            self._bytes += nbytes
            while self._bytes > self.max_bytes:
                _, (_, freed) = self._items.popitem(last=False)
                self._bytes -= freed
