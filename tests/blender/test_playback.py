"""Playback: the frames after the one shown are built by a background worker, so the next frame change finds its
mesh ready (no reconstruction on Blender's thread); frames already seen stay in memory (scrubbing back is instant);
a parameter change drops what was kept and builds again with the new value.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
api = addon.api
update, mesh_update = _support.addon_modules(addon, "blender.update", "blender.mesh_update")
_support.clear_scene()
scene = bpy.context.scene
scene.frame_set(25)
surface = _support.add_sample_sequence()
settings = surface.meniscus
settings.is_surface = False
settings.cube_size = 1.5
settings.smoothing_iterations = 2
settings.smoothing_reach = 0.0
settings.is_surface = True


class _OnlyTheWorkerReconstructs:
    """Fails the test if Blender's thread reads or reconstructs particles or puts a mesh in Blender's layout (the
    worker thread may: it prepares the mesh write too)."""

    def __enter__(self):
        import threading

        self.saved = api.reconstruct, api.read_particles, mesh_update._mesh_arrays
        main = threading.main_thread()

        def guarded(original):
            def call(*args, **kwargs):
                if threading.current_thread() is main:
                    raise AssertionError(f"{original.__name__} on Blender's thread during playback")
                return original(*args, **kwargs)
            return call

        api.reconstruct, api.read_particles, mesh_update._mesh_arrays = (guarded(function) for function in self.saved)
        return self

    def __exit__(self, *_exc):
        api.reconstruct, api.read_particles, mesh_update._mesh_arrays = self.saved


def wait_for_the_worker(timeout=120.0):
    deadline = time.monotonic() + timeout
    while not update._prefetcher.idle():
        check(time.monotonic() < deadline, "the prefetch worker did not finish")
        time.sleep(0.05)


def kept_keys():
    return list(update._memory.frames[surface.data.as_pointer()]._entries)


def test_the_next_frames_are_ready_when_played():
    scene.frame_set(25)
    wait_for_the_worker()
    with _OnlyTheWorkerReconstructs():
        for frame in (26, 27):
            started = time.perf_counter()
            scene.frame_set(frame)
            seconds = time.perf_counter() - started
            check("ready in memory" in settings.status and f"double_dam_break_00{frame}.vtk" in settings.status,
                  settings.status)
            check(len(surface.data.polygons) > 0, "empty mesh from memory")
            print(f"     frame {frame} from memory in {seconds:.3f} s")
            wait_for_the_worker()


def test_scrubbing_back_is_instant_and_prefetches_backwards():
    with _OnlyTheWorkerReconstructs():
        for frame in (26, 25):
            scene.frame_set(frame)
            check("ready in memory" in settings.status, settings.status)
    wait_for_the_worker()
    files = {key[1] for key in kept_keys()}
    check({22, 23, 24} <= files, f"playing backwards should build 24, 23, 22 ahead; kept: {sorted(files)}")


def test_a_parameter_change_drops_the_kept_frames():
    settings.smoothing_iterations = 3
    check("ready in memory" not in settings.status and not settings.status_is_error, settings.status)
    wait_for_the_worker()
    iterations = {dict(key[4])["smoothing_iterations"] for key in kept_keys()}
    check(iterations == {3}, f"frames of the old value kept: {iterations}")


def test_a_frame_not_built_ahead_reports_core_hand_off_and_blender():
    """The frame change built on Blender's thread: the status times each part, and the hand-off (the mesh in
    Blender's layout) is the core's (api.blender_mesh_arrays), not numpy's."""
    wait_for_the_worker()
    update.forget_frames(surface)
    calls = []
    original = api.blender_mesh_arrays

    def counted(*args, **kwargs):
        calls.append(len(args[0]))
        return original(*args, **kwargs)

    api.blender_mesh_arrays = counted
    try:
        scene.frame_set(30)
    finally:
        api.blender_mesh_arrays = original
    status = settings.status
    check(not settings.status_is_error and "ready in memory" not in status, status)
    timing = next((line for line in status.splitlines() if "hand-off" in line), "")
    check(timing.count(" s ") == 3 and " s core + " in timing and " s hand-off + " in timing and
          timing.endswith(" s in Blender"), status)
    check(calls and calls[0] == len(surface.data.polygons), f"the core made no arrays for this frame: {calls}")


_support.run(globals(), cleanup=addon.unregister)
