"""A surface's '//' paths follow the .blend as Blender's own do: storing one prints no warning (5.2 warns about a path
property not declared for '//'); Save As into another folder rewrites them (the surface still builds, before and
after reopening), Save Copy gives the copy rewritten paths and leaves the open file's alone, and a .blend moved with
its files keeps them (they resolve beside it); the default cache folder, once baked, follows as an explicit path.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import shutil
import sys
import tempfile
import warnings

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
app_handlers, paths = _support.addon_modules(addon, "blender.app_handlers", "blender.paths")
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_relative_paths_")
ROOT = _temporary.name
PROJECT = os.path.join(ROOT, "project")
os.makedirs(os.path.join(PROJECT, "p"))
for file_frame in (20, 21):
    shutil.copy(_support.SAMPLE_DIR / f"double_dam_break_00{file_frame}.vtk", os.path.join(PROJECT, "p"))
NAME = "double_dam_break_####.vtk"

_support.clear_scene()
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(PROJECT, "scene.blend"))
scene = bpy.context.scene
scene.frame_set(20)
surface = _support.add_sample_sequence(os.path.join(PROJECT, "p", "double_dam_break_0020.vtk"))
surface_name = surface.name
surface.meniscus.cube_size = 2.0  # coarse: the paths are tested here
surface.meniscus.smoothing_iterations = 0


def slashes(path):
    """A stored path with '/' separators: Blender writes relative paths with the platform's own ('\\' on Windows)."""
    return path.replace("\\", "/")


def settings():
    return bpy.data.objects[surface_name].meniscus


def builds(frame=21):
    """Whether the surface builds a mesh at frame (a frame it did not show before)."""
    scene = bpy.context.scene
    scene.frame_set(frame)
    obj = bpy.data.objects[surface_name]
    return not obj.meniscus.status_is_error and len(obj.data.polygons) > 0, obj.meniscus.status


def test_storing_a_blend_relative_path_prints_no_warning():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        settings().file_pattern = "//p/" + NAME
        settings().cache_pattern = "//cache/fluid_####.npz"
    check(not caught, [str(warning.message) for warning in caught])
    ok, status = builds(20)
    check(ok, status)


def test_save_as_into_another_folder_keeps_the_particle_paths():
    other = os.path.join(ROOT, "elsewhere", "shots")
    os.makedirs(other)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(other, "scene.blend"))
    check(slashes(settings().file_pattern) == "//../../project/p/" + NAME, settings().file_pattern)
    check(slashes(settings().cache_pattern) == "//../../project/cache/fluid_####.npz", settings().cache_pattern)
    ok, status = builds(21)
    check(ok, f"after Save As: {status}")
    bpy.ops.wm.open_mainfile(filepath=os.path.join(other, "scene.blend"))
    check(slashes(settings().file_pattern) == "//../../project/p/" + NAME, settings().file_pattern)
    ok, status = builds(20)
    check(ok, f"reopened: {status}")


def test_save_copy_rewrites_the_copy_only():
    copy = os.path.join(ROOT, "copies", "copy.blend")
    os.makedirs(os.path.dirname(copy))
    opened = bpy.data.filepath
    bpy.ops.wm.save_as_mainfile(filepath=copy, copy=True)
    check(bpy.data.filepath == opened and slashes(settings().file_pattern) == "//../../project/p/" + NAME,
          (bpy.data.filepath, settings().file_pattern))
    ok, status = builds(21)
    check(ok, f"the open file after Save Copy: {status}")
    bpy.ops.wm.open_mainfile(filepath=copy)
    check(slashes(settings().file_pattern) == "//../project/p/" + NAME, settings().file_pattern)
    ok, status = builds(20)
    check(ok, f"the copy: {status}")


def test_a_blend_moved_with_its_files_keeps_its_paths():
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(PROJECT, "scene.blend"))
    check(slashes(settings().file_pattern) == "//p/" + NAME, settings().file_pattern)
    # 3.4 does not tell the add-on where Save As writes: that file keeps the paths of the folder it came from (its
    # next load rewrites them) until it is saved again, as here, before it is moved.
    bpy.ops.wm.save_mainfile()
    moved = os.path.join(ROOT, "moved")
    shutil.copytree(PROJECT, moved)  # the original stays: the moved .blend must use its own files
    os.remove(os.path.join(moved, "p", "double_dam_break_0021.vtk"))  # tells the two apart
    bpy.ops.wm.open_mainfile(filepath=os.path.join(moved, "scene.blend"))
    check(slashes(settings().file_pattern) == "//p/" + NAME, settings().file_pattern)
    ok, status = builds(20)
    check(ok, status)
    ok, status = builds(21)
    check(not ok and os.path.join(moved, "p") in status, f"frame 21 was read from the original: {status}")


def test_the_default_cache_folder_follows_once_baked():
    obj = bpy.data.objects[surface_name]
    obj.meniscus.cache_pattern = ""  # the default: meniscus_cache/<object>/ beside the .blend
    result = bpy.ops.meniscus.bake(object_name=surface_name, use_surface_range=False, frame_start=20, frame_end=20)
    check(result == {"FINISHED"}, result)
    other = os.path.join(ROOT, "after_bake")
    os.makedirs(other)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(other, "scene.blend"))
    stored = settings().cache_pattern
    check(slashes(stored).startswith("//../moved/meniscus_cache/"), stored)
    check(os.path.isfile(bpy.path.abspath(stored).replace("####", "0020")), f"{stored}: the baked frame is not there")


def stored_paths():
    return settings().file_pattern, settings().cache_pattern, settings().get(paths.FOLDER_PROPERTY)


def test_a_failed_save_leaves_the_open_files_paths():
    opened, before = bpy.data.filepath, stored_paths()
    not_a_folder = os.path.join(ROOT, "not_a_folder")
    open(not_a_folder, "w").close()
    try:  # the parent is a file: Blender cannot write there, after save_pre has run
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(not_a_folder, "shots", "scene.blend"))
    except RuntimeError:  # the operator's error report
        pass
    check(bpy.data.filepath == opened, bpy.data.filepath)
    check(stored_paths() == before, f"after a failed save: {stored_paths()}, before it: {before}")


def test_undo_after_save_as_rebases_the_restored_paths():
    before = stored_paths()
    other = os.path.join(ROOT, "undone", "shots")
    os.makedirs(other)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(other, "scene.blend"))
    after = stored_paths()
    check(after != before, after)
    # Ctrl+Z to a step from before the Save As restores the properties it stored (background Blender has no undo
    # stack: written here as the step holds them), and runs undo_post.
    obj = bpy.data.objects[surface_name]
    obj.meniscus["file_pattern"], obj.meniscus["cache_pattern"], obj.meniscus[paths.FOLDER_PROPERTY] = before
    app_handlers.meniscus_undo_redo_post()
    check(stored_paths() == after, f"after undo: {stored_paths()}, the file's folder needs {after}")


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
