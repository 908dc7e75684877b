"""Export for Renders Without Meniscus exports what a render would show: frames built at the render cube size (not
the viewport's) when nothing was baked, and frames that cannot be built (30 missing, 31 truncated) handled by the
surface's "If a Frame Fails": Stop fails the export naming the frames and writes no file, Hold and Empty export the
held or empty frame and list those frames in the result the operator reports.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
cache = addon.cache
native_cache, update, app_handlers, busy_files = _support.addon_modules(
    addon, "blender.native_cache", "blender.update", "blender.app_handlers", "busy_files")
# ignore_cleanup_errors: on Windows Blender still holds the played .abc open at the end.
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_export_render_", ignore_cleanup_errors=True)
FILES, BROKEN = _support.failing_sequence(_temporary.name)  # 30 missing, 31 truncated

_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence(os.path.join(FILES, "double_dam_break_0028.vtk"))
settings = surface.meniscus
settings.is_surface = False
settings.cube_size = 1.5
settings.render_cube_size = 1.0
settings.smoothing_iterations = 0
settings.cache_pattern = os.path.join(_temporary.name, "cache", "fluid_####.npz")  # the .abc goes beside it
settings.is_surface = True
ABC = os.path.join(_temporary.name, "cache", f"{bpy.path.clean_name(surface.name)}.abc")


def evaluated_counts(frame):
    scene.frame_set(frame)
    mesh = surface.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
    return len(mesh.vertices), len(mesh.polygons)


def built_counts(file_frame, for_render):
    """Vertices and triangles of a file frame reconstructed as the add-on does for the viewport or a render."""
    arguments = update.reconstruction_arguments(settings, for_render)
    wanted = cache.parse_attribute_names(settings.attribute_names)
    path = os.path.join(FILES, f"double_dam_break_{file_frame:04d}.vtk")
    mesh = cache.reconstruct_file(path, arguments, wanted).mesh
    return len(mesh.vertices), len(mesh.triangles)


def refuses_without_alembic():
    """Debian's 3.4 has no Alembic: the export refuses, saying why (and the rest of a test has nothing to check)."""
    if native_cache.can_export():
        return False
    try:
        native_cache.export_alembic(surface, scene, 28, 29, ABC)
    except native_cache.NativeCacheError as error:
        check("without Alembic" in str(error) and not settings.use_native_cache, str(error))
        return True
    raise AssertionError("an export without Alembic did not refuse")


def export_with(policy, first, last):
    native_cache.remove_native_cache(surface)
    settings.render_failure = policy
    scene.frame_start, scene.frame_end = first, last
    return native_cache.export_alembic(surface, scene, first, last, ABC)


def test_unbaked_frames_are_exported_at_the_render_cube_size():
    if refuses_without_alembic():
        return
    render = {frame: built_counts(frame, True) for frame in (28, 29)}
    viewport = {frame: built_counts(frame, False) for frame in (28, 29)}
    check(all(render[frame][0] > viewport[frame][0] for frame in render), f"render {render}, viewport {viewport}")
    scene.frame_set(28)  # the viewport shows its own cube size before the export
    check(len(surface.data.vertices) == viewport[28][0], (len(surface.data.vertices), viewport))
    scene.frame_start, scene.frame_end = 28, 29
    check(bpy.ops.meniscus.export_alembic(object_name=surface.name) == {"FINISHED"}, "the operator failed")
    check(settings.use_native_cache and os.path.exists(ABC), "the surface does not play the exported file")
    for frame in (29, 28):
        check(evaluated_counts(frame) == render[frame], f"frame {frame}: {evaluated_counts(frame)}, the render "
                                                        f"size gives {render[frame]}, the viewport's {viewport[frame]}")
    result = export_with("STOP", 28, 29)
    check(result.frames == 2 and result.cube_size == 1.0 and not result.failed and result.path == ABC, result)
    text = native_cache.summary(result)
    check("Wrote 2 frames at render cube size 1 to" in text and ABC in text, text)


def test_stop_fails_the_export_naming_the_frames():
    if refuses_without_alembic():
        return
    export_with("EMPTY", 28, 29)  # an earlier good export, which a failed one must leave whole and playing
    earlier = os.path.getsize(ABC), evaluated_counts(28)
    settings.render_failure = "STOP"
    scene.frame_start, scene.frame_end = 29, 32
    try:
        bpy.ops.meniscus.export_alembic(object_name=surface.name)
    except RuntimeError as error:  # the operator's error report, as a script sees it
        message = str(error)
    else:
        raise AssertionError("the export did not fail")
    check("frames 30, 31 cannot be built" in message and "Stop the Render" in message, message)
    check("double_dam_break_0030.vtk" in message and BROKEN in message, message)
    check(settings.use_native_cache and [m.name for m in surface.modifiers] == [native_cache.MODIFIER_NAME] and
          native_cache.playing_file(surface) == ABC, list(surface.modifiers))
    check((os.path.getsize(ABC), evaluated_counts(28)) == earlier, "the failed export changed the earlier file")
    check(sorted(os.listdir(os.path.dirname(ABC))) == [os.path.basename(ABC)], os.listdir(os.path.dirname(ABC)))


def test_hold_exports_the_last_good_frame_and_lists_the_failed_ones():
    if refuses_without_alembic():
        return
    result = export_with("HOLD", 29, 32)
    good = built_counts(29, True)
    check(sorted(result.failed) == [30, 31], result.failed)
    check(all(held == "double_dam_break_0029.vtk" for _, held in result.failed.values()), result.failed)
    check(BROKEN in result.failed[31][0], result.failed[31])
    for frame in (30, 31):
        check(evaluated_counts(frame) == good, f"frame {frame}: {evaluated_counts(frame)}, frame 29: {good}")
    check(evaluated_counts(32) == built_counts(32, True), evaluated_counts(32))
    text = native_cache.summary(result)
    check("Wrote 4 frames at render cube size 1" in text and
          "held: 30 (double_dam_break_0029.vtk), 31 (double_dam_break_0029.vtk)" in text, text)


def test_empty_exports_empty_frames_and_lists_them():
    if refuses_without_alembic():
        return
    result = export_with("EMPTY", 29, 32)
    check(sorted(result.failed) == [30, 31] and all(held is None for _, held in result.failed.values()),
          result.failed)
    check(evaluated_counts(30) == (0, 0) and evaluated_counts(31) == (0, 0),
          (evaluated_counts(30), evaluated_counts(31)))
    check(evaluated_counts(29) == built_counts(29, True), evaluated_counts(29))
    text = native_cache.summary(result)
    check("Wrote 4 frames at render cube size 1" in text and "empty: 30, 31" in text, text)
    # Through the operator too: it completes (the report lists the frames as a warning).
    native_cache.remove_native_cache(surface)
    check(bpy.ops.meniscus.export_alembic(object_name=surface.name) == {"FINISHED"}, "the operator failed")


def test_reexport_over_the_played_file():
    """Exporting again over the file the surface plays: the cache file data-block left reading it is released first;
    where the file cannot be renamed over (Windows, while Blender still holds it open) the finished export is written
    over it in place; where it cannot be written either (another program reading it), the export waits for it a
    while, then fails saying so, removes its partial file and plays the earlier one again."""
    if refuses_without_alembic():
        return
    export_with("EMPTY", 28, 29)
    settings.render_failure = "EMPTY"
    replace, copyfile, wait = native_cache.os.replace, native_cache.shutil.copyfile, busy_files.WAIT_SECONDS

    def refused(*_args):  # what Windows says while another process holds the file open
        raise PermissionError(13, "Permission denied")

    refusals = []

    def refused_twice(*args):  # a reader that lets go after a moment
        if len(refusals) < 2:
            refusals.append(args)
            refused()
        return copyfile(*args)

    native_cache.os.replace = refused
    try:
        result = native_cache.export_alembic(surface, scene, 28, 29, ABC)  # written over in place
        check(result.path == ABC and native_cache.playing_file(surface) == ABC, result)
        check(sorted(os.listdir(os.path.dirname(ABC))) == [os.path.basename(ABC)], os.listdir(os.path.dirname(ABC)))
        native_cache.shutil.copyfile = refused_twice
        result = native_cache.export_alembic(surface, scene, 28, 29, ABC)  # waited for the reader
        check(len(refusals) == 2 and result.path == ABC and native_cache.playing_file(surface) == ABC, result)
        # What the refused export must leave as it is: measured here, as two exports of the same frames can differ
        # in a few bytes (seen under Wine).
        with open(ABC, "rb") as played:
            earlier = played.read(), evaluated_counts(28)
        native_cache.shutil.copyfile = refused
        busy_files.WAIT_SECONDS = 0.3
        native_cache.export_alembic(surface, scene, 28, 29, ABC)
    except native_cache.NativeCacheError as error:
        message = str(error)
    else:
        raise AssertionError("the export did not fail")
    finally:
        native_cache.os.replace, native_cache.shutil.copyfile = replace, copyfile
        busy_files.WAIT_SECONDS = wait
    check(f"{ABC} cannot be replaced (Permission denied; waited 0.3 s)" in message, message)
    check(sorted(os.listdir(os.path.dirname(ABC))) == [os.path.basename(ABC)], os.listdir(os.path.dirname(ABC)))
    with open(ABC, "rb") as played:
        now = played.read(), evaluated_counts(28)
    check(native_cache.playing_file(surface) == ABC and now == earlier,
          f"plays {native_cache.playing_file(surface)}; file size and frame 28's counts {len(now[0]), now[1]}, "
          f"before {len(earlier[0]), earlier[1]}")
    result = native_cache.export_alembic(surface, scene, 28, 29, ABC)
    check(result.path == ABC and native_cache.playing_file(surface) == ABC, result)
    unused = [cache_file.filepath for cache_file in bpy.data.cache_files if cache_file.users == 0]
    check(not unused, f"cache files left reading nothing: {unused}")
    if os.name == "nt":  # the same with a real Windows reader, which lets go after a second
        hold_without_sharing(ABC, seconds=1.0)
        result = native_cache.export_alembic(surface, scene, 28, 29, ABC)
        check(result.path == ABC and native_cache.playing_file(surface) == ABC, result)


def hold_without_sharing(path, seconds):
    """Opens path as many Windows programs read a file, sharing neither delete nor write access (so that it can be
    neither renamed over nor written), and closes it after seconds."""
    import ctypes
    import threading
    kernel32 = ctypes.WinDLL("kernel32", use_last_error=True)
    kernel32.CreateFileW.restype = ctypes.c_void_p
    kernel32.CreateFileW.argtypes = [ctypes.c_wchar_p, ctypes.c_uint32, ctypes.c_uint32, ctypes.c_void_p,
                                     ctypes.c_uint32, ctypes.c_uint32, ctypes.c_void_p]
    kernel32.CloseHandle.argtypes = [ctypes.c_void_p]
    generic_read, file_share_read, open_existing = 0x80000000, 1, 3
    handle = kernel32.CreateFileW(path, generic_read, file_share_read, None, open_existing, 0, None)
    check(handle not in (None, ctypes.c_void_p(-1).value), f"cannot open {path}: {ctypes.get_last_error()}")
    threading.Timer(seconds, kernel32.CloseHandle, (handle,)).start()


def render_still(frame):
    """What F12 does to the surface at a frame (render_init, render_pre, the end of the render); its vertex count."""
    scene.frame_set(frame)
    app_handlers.meniscus_render_init(scene)
    try:
        app_handlers.meniscus_render_pre(scene)
        return len(surface.data.vertices)
    finally:
        app_handlers.meniscus_render_done(scene)


def test_a_render_after_a_failed_export_applies_its_own_policy():
    """A Stop export that failed at the frame shown must not leave that frame's empty surface looking done to a
    later render: F12 applies its own "If a Frame Fails", and so does a second F12 in a row."""
    if refuses_without_alembic():
        return
    native_cache.remove_native_cache(surface)
    viewport_cube_size = settings.cube_size
    settings.cube_size = settings.render_cube_size  # the viewport then builds what a render builds: the same key
    try:
        scene.frame_set(31)
        try:
            export_with("STOP", 29, 31)
        except native_cache.NativeCacheError:
            pass
        else:
            raise AssertionError("the export did not fail")
        check(scene.frame_current == 31 and len(surface.data.vertices) == 0, len(surface.data.vertices))
        settings.render_failure = "HOLD"
        held = built_counts(29, True)[0]
        check(render_still(31) == held, f"{len(surface.data.vertices)} vertices, frame 29 has {held}; status "
                                        f"{settings.status!r}")
        # The next F12 at the same failed frame applies its own policy too, not what the previous render left.
        settings.render_failure = "EMPTY"
        check(render_still(31) == 0, f"{len(surface.data.vertices)} vertices; status {settings.status!r}")
    finally:
        settings.cube_size = viewport_cube_size


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
