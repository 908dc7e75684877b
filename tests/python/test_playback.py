"""The playback cache and the background prefetcher (bpy-free): memory bound, least recently used out, stale work
dropped, results of cleared caches thrown away, waiting for a frame being built."""
import threading
import time

import numpy as np

from meniscus import playback


def _array(kilobytes):
    return np.zeros(kilobytes * 1024, dtype=np.uint8)


def test_cache_keeps_the_recently_used_within_its_budget():
    cache = playback.FrameCache(budget_bytes=250 * 1024)
    for key in "abc":
        cache.put(key, _array(100))
    assert "a" not in cache and "b" in cache and "c" in cache and cache.bytes == 200 * 1024
    cache.get("b")  # used: now the newest
    cache.put("d", _array(100))
    assert "c" not in cache and "b" in cache and "d" in cache
    cache.put("huge", _array(1000))  # alone over the budget: kept, the host is about to show it
    assert len(cache) == 1 and "huge" in cache


def test_a_shared_budget_holds_across_caches_dropping_the_least_recently_used_of_any():
    budget = playback.MemoryBudget(350 * 1024)
    first, second = playback.FrameCache(1 << 30, shared=budget), playback.FrameCache(1 << 30, shared=budget)
    first.put("a", _array(100))
    first.put("b", _array(100))
    second.put("x", _array(100))
    first.get("a")  # used: "b" is now the least recently used of all
    second.put("y", _array(100))
    assert "b" not in first and "a" in first and "x" in second and "y" in second
    assert budget.bytes == first.bytes + second.bytes == 300 * 1024
    second.put("z", _array(200))  # 500 KiB: second's "x" and "y" go; first's only result is its newest, kept
    assert "x" not in second and "y" not in second and "z" in second and "a" in first
    assert budget.bytes == 300 * 1024
    del second  # a cache nobody holds (its surface was deleted) stops counting
    assert budget.bytes == first.bytes == 100 * 1024


def test_take_returns_a_result_once_and_frees_its_bytes():
    cache = playback.FrameCache(budget_bytes=1 << 20)
    cache.put("frame 30", _array(100))
    cache.put("frame 31", _array(50))
    assert cache.take("frame 30") is not None
    assert "frame 30" not in cache and cache.bytes == 50 * 1024
    assert cache.take("frame 30") is None


def test_result_bytes_counts_arrays_inside_objects_once():
    class Result:
        def __init__(self):
            shared = _array(10)
            self.mesh = {"vertices": shared, "again": shared, "normals": _array(5)}
            self.count = 3

    assert playback.result_bytes(Result()) == 15 * 1024


def test_a_result_built_before_clear_is_dropped():
    cache = playback.FrameCache(budget_bytes=1 << 20)
    generation = cache.generation
    cache.clear()
    assert not cache.put("a", _array(1), generation=generation) and "a" not in cache
    assert cache.put("a", _array(1), generation=cache.generation) and "a" in cache


def _wait_idle(prefetcher, timeout=10.0):
    deadline = time.monotonic() + timeout
    while not prefetcher.idle() and time.monotonic() < deadline:
        time.sleep(0.01)
    assert prefetcher.idle()


def test_prefetcher_builds_in_order_and_drops_work_no_longer_wanted():
    cache = playback.FrameCache(budget_bytes=1 << 20)
    prefetcher = playback.Prefetcher()
    release = threading.Event()
    built = []

    def build(key, blocking=False):
        def run():
            if blocking:
                release.wait(10)
            built.append(key)
            return _array(1)
        return run

    try:
        prefetcher.want(cache, [(1, build(1, blocking=True)), (2, build(2)), (3, build(3))])
        deadline = time.monotonic() + 10
        while not prefetcher.is_building(cache, 1) and time.monotonic() < deadline:
            time.sleep(0.01)
        # The user jumped: 2 and 3 are no longer wanted, 7 and 8 are.
        prefetcher.want(cache, [(7, build(7)), (8, build(8))])
        release.set()
        _wait_idle(prefetcher)
        assert built == [1, 7, 8] and all(key in cache for key in (1, 7, 8))
    finally:
        prefetcher.stop()


def test_waiting_for_a_frame_being_built_and_a_cleared_cache():
    cache = playback.FrameCache(budget_bytes=1 << 20)
    prefetcher = playback.Prefetcher()
    started, release = threading.Event(), threading.Event()

    def slow():
        started.set()
        release.wait(10)
        return _array(1)

    try:
        prefetcher.want(cache, [("a", slow), ("b", lambda: _array(1))])
        assert started.wait(10)
        threading.Timer(0.2, release.set).start()
        assert prefetcher.wait_for(cache, "a", timeout=10) is not None  # waited for the build under way
        assert prefetcher.wait_for(cache, "never wanted", timeout=10) is None  # at once: nobody builds it
        _wait_idle(prefetcher)
        # A build finishing after clear() (a parameter changed meanwhile) is not kept.
        started.clear(), release.clear()
        prefetcher.want(cache, [("c", slow)])
        assert started.wait(10)
        cache.clear()
        release.set()
        _wait_idle(prefetcher)
        assert "c" not in cache and len(cache) == 0
    finally:
        prefetcher.stop()
