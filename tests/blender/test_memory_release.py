"""Playback memory: a surface deleted or unlinked releases the frames kept for it (measured by the playback caches'
own accounting, and a kept mesh array must be freed; the process's resident memory is printed beside it, though the
allocator need not return freed memory to the system), and the playback budget holds for all surfaces together.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import gc
import os
import sys
import time
import weakref

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
update = _support.addon_modules(addon, "blender.update")
_support.clear_scene()
scene = bpy.context.scene


def add_surface():
    scene.frame_set(20)
    surface = _support.add_sample_sequence()
    settings = surface.meniscus
    settings.is_surface = False
    settings.cube_size = 1.5
    settings.smoothing_iterations = 0
    settings.is_surface = True
    return surface


def scrub(frames):
    """Plays frames in the viewport and waits for the worker's build-ahead to finish (so the accounting is still)."""
    for frame in frames:
        scene.frame_set(frame)
    deadline = time.monotonic() + 120.0
    while not update._prefetcher.idle():
        check(time.monotonic() < deadline, "the prefetch worker did not finish")
        time.sleep(0.05)


def held():
    """Bytes of the frames kept for playback: every surface's frame cache, by its own accounting."""
    return sum(frames.bytes for frames in update._memory.frames.values())


def resident_megabytes():
    if not hasattr(os, "sysconf"):  # Windows (also under Wine, where /proc of the host can be read)
        return float("nan")
    try:
        with open("/proc/self/statm") as statm:
            return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2 ** 20
    except (OSError, ValueError):  # not Linux: the accounting is what the test checks
        return float("nan")


def test_deleted_and_unlinked_surfaces_release_their_frames():
    for cycle, how in enumerate(("deleted", "unlinked", "deleted")):
        surface = add_surface()
        scrub(range(20, 23))
        kept = held()
        check(kept > 1 << 20, f"cycle {cycle}: {kept} bytes kept after scrubbing")
        frames = update._memory.frames[surface.data.as_pointer()]
        vertices = weakref.ref(next(iter(frames._entries.values()))[0].mesh.vertices)
        del frames
        before = resident_megabytes()
        if how == "deleted":
            bpy.data.objects.remove(surface, do_unlink=True)  # what Delete does (the mesh stays, unused)
        else:
            for collection in list(surface.users_collection):
                collection.objects.unlink(surface)
        bpy.context.view_layer.update()  # the depsgraph update that follows a deletion in the UI
        check(held() == 0, f"cycle {cycle}: {held()} bytes still held for the {how} surface")
        check(update.held_bytes() == 0, f"the shared budget counts {update.held_bytes()} bytes")
        gc.collect()
        check(vertices() is None, f"cycle {cycle}: a kept frame's vertices are still referenced")
        print(f"cycle {cycle} ({how}): {kept / 2 ** 20:.1f} MiB of frames released; resident "
              f"{before:.0f} -> {resident_megabytes():.0f} MiB")


def test_a_renamed_surface_keeps_its_frames():
    surface = add_surface()
    scrub(range(20, 23))
    pointer = surface.data.as_pointer()
    kept = update._memory.frames[pointer].bytes
    surface.name = "renamed surface"
    bpy.context.view_layer.update()
    check(update.release_removed_surfaces() == 0, "the renamed surface was taken for a removed one")
    check(pointer in update._memory.frames and update._memory.frames[pointer].bytes == kept,
          f"{held()} bytes held, {kept} before the rename")
    bpy.data.objects.remove(surface, do_unlink=True)  # then deleted under its new name: released as before
    bpy.context.view_layer.update()
    check(pointer not in update._memory.frames and held() == 0, f"{held()} bytes still held")


def test_the_playback_budget_holds_for_all_surfaces_together():
    first, second = add_surface(), add_surface()
    scrub(range(20, 23))
    frame_bytes = max(frames.bytes / len(frames) for frames in update._memory.frames.values())
    budget = update._memory.budget
    saved = budget.budget_bytes
    budget.budget_bytes = int(4 * frame_bytes)  # fewer frames than the two surfaces hold
    try:
        scrub(range(23, 27))
        check(held() <= budget.budget_bytes, f"{held()} bytes held over the budget of {budget.budget_bytes}")
        for obj in (first, second):
            frames = update._memory.frames[obj.data.as_pointer()]
            check(len(frames) >= 1, f"{obj.name} lost its current frame")
    finally:
        budget.budget_bytes = saved


def _cleanup():
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
