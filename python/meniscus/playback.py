"""Playback that keeps up: reconstructed frames kept in memory, and the next ones built in the background.

Two pieces, both free of bpy (a host such as the Blender add-on decides what is wanted and shows the results on its
own thread):
- FrameCache: results by key, the least recently used dropped once their bytes pass a budget (its own, or a
  MemoryBudget shared with other caches: one surface's frames then make room for another's);
- Prefetcher: one worker thread that builds wanted keys into a FrameCache. The wanted list is replaced as a whole
  on each call (work for frames no longer wanted is dropped, never started); a result built for a cache that was
  cleared meanwhile is thrown away. The core releases the GIL while it reconstructs, so the host's thread runs on.

    cache = FrameCache(budget_bytes=1 << 30)
    prefetcher = Prefetcher()
    prefetcher.want(cache, [(key, lambda: build(frame)) for key, frame in next_frames])
    result = cache.get(key) or prefetcher.wait_for(cache, key, timeout=2.0) or build_now()
"""
import collections
import itertools
import threading
import weakref
from typing import Callable, Hashable, List, Optional, Tuple

import numpy as np


def result_bytes(value) -> int:
    """Memory held by a result: the bytes of every numpy array reachable through its attributes (meshes,
    attribute dictionaries), each counted once."""
    seen = set()
    total = 0
    stack = [value]
    while stack:
        item = stack.pop()
        if id(item) in seen:
            continue
        seen.add(id(item))
        if isinstance(item, np.ndarray):
            total += item.nbytes
        elif isinstance(item, dict):
            stack.extend(item.values())
        elif isinstance(item, (list, tuple)):
            stack.extend(item)
        elif hasattr(item, "__dict__"):
            stack.extend(vars(item).values())
        elif hasattr(item, "__dataclass_fields__"):
            stack.extend(getattr(item, name) for name in item.__dataclass_fields__)
    return total


class MemoryBudget:
    """A byte budget shared by several FrameCaches: when their results together pass it, the least recently used
    result of any of them is dropped first (each cache's newest result is kept). Thread-safe."""

    def __init__(self, budget_bytes: int):
        self.budget_bytes = int(budget_bytes)
        self._caches = weakref.WeakSet()
        self._lock = threading.Lock()
        self._clock = itertools.count()  # use order across the caches

    def tick(self) -> int:
        return next(self._clock)

    def add(self, cache: "FrameCache") -> None:
        with self._lock:
            self._caches.add(cache)

    @property
    def bytes(self) -> int:
        with self._lock:
            caches = list(self._caches)
        return sum(cache.bytes for cache in caches)

    def enforce(self) -> None:
        """Drops the least recently used results of the caches until they fit (never a cache's newest). Takes one
        cache's lock at a time, never while holding another's."""
        with self._lock:
            caches = list(self._caches)
            total = sum(cache.bytes for cache in caches)
            while total > self.budget_bytes:
                candidates = [(used, cache) for cache in caches for used in [cache.oldest_use()] if used is not None]
                if not candidates:
                    return
                _, oldest = min(candidates, key=lambda candidate: candidate[0])
                total -= oldest.drop_oldest()


class FrameCache:
    """Results by key, least recently used first out once their bytes exceed budget_bytes, or, with shared, once the
    results of every cache sharing that MemoryBudget exceed its budget (the newest result is always kept, even
    alone over the budget: the host is about to show it). Thread-safe."""

    def __init__(self, budget_bytes: int, shared: Optional[MemoryBudget] = None):
        self.budget_bytes = int(budget_bytes)
        self.shared = shared
        self._entries = collections.OrderedDict()  # key -> (value, bytes, last use)
        self._bytes = 0
        self._lock = threading.Lock()
        self._clock = shared.tick if shared is not None else itertools.count().__next__
        self.generation = 0  # raised by clear(): results of work started before it are not stored
        if shared is not None:
            shared.add(self)

    def get(self, key: Hashable):
        with self._lock:
            entry = self._entries.get(key)
            if entry is None:
                return None
            self._entries[key] = (entry[0], entry[1], self._clock())
            self._entries.move_to_end(key)
            return entry[0]

    def oldest_use(self) -> Optional[int]:
        """When the least recently used result that may be dropped was last used (None: none may)."""
        with self._lock:
            if len(self._entries) < 2:
                return None
            return next(iter(self._entries.values()))[2]

    def drop_oldest(self) -> int:
        """Drops the least recently used result unless it is the only one; returns its bytes (0 if none)."""
        with self._lock:
            if len(self._entries) < 2:
                return 0
            _, (_, dropped, _) = self._entries.popitem(last=False)
            self._bytes -= dropped
            return dropped

    def take(self, key: Hashable):
        """The result of key, removed from the cache (a render uses each frame once: it is not kept)."""
        with self._lock:
            entry = self._entries.pop(key, None)
            if entry is None:
                return None
            self._bytes -= entry[1]
            return entry[0]

    def __contains__(self, key: Hashable) -> bool:
        with self._lock:
            return key in self._entries

    def put(self, key: Hashable, value, size: Optional[int] = None, generation: Optional[int] = None) -> bool:
        """Stores a result; returns False when it was built before the last clear() (it is dropped)."""
        size = result_bytes(value) if size is None else int(size)
        with self._lock:
            if generation is not None and generation != self.generation:
                return False
            old = self._entries.pop(key, None)
            if old is not None:
                self._bytes -= old[1]
            self._entries[key] = (value, size, self._clock())
            self._bytes += size
            while self.shared is None and self._bytes > self.budget_bytes and len(self._entries) > 1:
                _, (_, dropped, _) = self._entries.popitem(last=False)
                self._bytes -= dropped
        if self.shared is not None:  # outside this cache's lock: the budget takes the caches' locks one by one
            self.shared.enforce()
        return True

    def clear(self) -> None:
        with self._lock:
            self._entries.clear()
            self._bytes = 0
            self.generation += 1

    @property
    def bytes(self) -> int:
        with self._lock:
            return self._bytes

    def __len__(self) -> int:
        with self._lock:
            return len(self._entries)


Job = Tuple[Hashable, Callable[[], object]]


class Prefetcher:
    """One background thread building wanted results into their caches, in the order wanted."""

    def __init__(self):
        self._condition = threading.Condition()
        self._wanted = collections.OrderedDict()  # (id(cache), key) -> (cache, key, build, generation)
        self._building = None  # (id(cache), key) being built now
        self._thread = None
        self._stopped = False
        self.failures = {}  # key -> message of the last failed build (the host builds it itself and reports)

    def want(self, cache: FrameCache, jobs: List[Job]) -> None:
        """Replaces what is wanted for this cache by jobs (keys already cached are skipped); nearest first."""
        with self._condition:
            for slot in [slot for slot in self._wanted if slot[0] == id(cache)]:
                del self._wanted[slot]
            for key, build in jobs:
                if key not in cache and (id(cache), key) != self._building:
                    self._wanted[(id(cache), key)] = (cache, key, build, cache.generation)
            if self._wanted and not self._stopped:
                self._ensure_thread()
            self._condition.notify_all()

    def forget(self, cache: FrameCache) -> None:
        """Drops the wanted work of a cache (a parameter changed; its results would be stale)."""
        self.want(cache, [])

    def is_building(self, cache: FrameCache, key: Hashable) -> bool:
        with self._condition:
            return self._building == (id(cache), key)

    def idle(self) -> bool:
        with self._condition:
            return not self._wanted and self._building is None

    def wait_for(self, cache: FrameCache, key: Hashable, timeout: float):
        """The result of key once the worker has built it, when it is building it now; None after timeout, or at
        once when it is not (a wanted key not started yet is taken off the list: the host builds it itself now)."""
        slot = (id(cache), key)
        with self._condition:
            if self._building != slot:
                self._wanted.pop(slot, None)
                return cache.get(key)
            self._condition.wait_for(lambda: self._building != slot or self._stopped, timeout)
        return cache.get(key)

    def stop(self) -> None:
        with self._condition:
            self._stopped = True
            self._wanted.clear()
            self._condition.notify_all()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=30)
            if thread.is_alive():  # still in a build: this prefetcher stays stopped
                return
        self._thread = None
        with self._condition:
            self._stopped = False  # usable again (the add-on registered anew)

    def _ensure_thread(self):
        if self._thread is None or not self._thread.is_alive():
            self._thread = threading.Thread(target=self._run, name="meniscus-prefetch", daemon=True)
            self._thread.start()

    def _run(self):
        while True:
            with self._condition:
                self._building = None
                self._condition.notify_all()
                self._condition.wait_for(lambda: self._wanted or self._stopped)
                if self._stopped:
                    return
                slot, (cache, key, build, generation) = self._wanted.popitem(last=False)
                self._building = slot
            try:
                value = build()
            except Exception as error:  # reported by the host when it builds the frame itself
                self.failures[key] = str(error) or type(error).__name__
                continue
            cache.put(key, value, generation=generation)
