"""Renders that fail loudly: a frame whose surface cannot be built (a missing file, a broken one) stops a final render
from the command line with exit status 1 and a message naming the file and the reason; the surface setting
"If a Frame Fails" holds the last good frame or renders an empty surface instead; the viewport is unchanged.

Each render runs in a new process from a saved .blend, as a farm node does (`blender -b scene.blend -f 30`).
"""
import contextlib
import io
import os
import shutil
import sys
import tempfile

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_render_failure_")
FILES, BROKEN = _support.failing_sequence(_temporary.name)  # 30 missing, 31 truncated

_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence(os.path.join(FILES, "double_dam_break_0028.vtk"))
surface.meniscus.cube_size = surface.meniscus.render_cube_size = 1.5  # the render path matters here, not the surface
surface.meniscus.smoothing_iterations = 0
_support.make_small_render(scene, os.path.join(_temporary.name, "out", "frame_####"))


def render_saved_copy(policy, first, last=None):
    """Saves the scene with the policy and renders first..last in a new process; returns (exit status, output,
    the images written, the status lines the surface showed at each rendered frame)."""
    surface.meniscus.render_failure = policy
    blend = os.path.join(_temporary.name, f"{policy.lower()}.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True)
    shutil.rmtree(os.path.join(_temporary.name, "out"), ignore_errors=True)
    completed = _support.render_in_new_process(blend, first, last, report=f"bpy.data.objects[{surface.name!r}]")
    written = sorted(os.listdir(os.path.join(_temporary.name, "out"))) if os.path.isdir(
        os.path.join(_temporary.name, "out")) else []
    reports = [line.split(" ", 1)[1] for line in completed.stdout.splitlines() if line.startswith("RENDERED ")]
    return completed.returncode, completed.stdout, written, reports


def test_viewport_shows_a_failed_frame_empty_and_goes_on():
    scene.frame_set(30)
    check(surface.meniscus.status_is_error and "double_dam_break_0030.vtk" in surface.meniscus.status,
          surface.meniscus.status)
    check(len(surface.data.polygons) == 0, "a failed frame must not show another frame's mesh")
    scene.frame_set(29)
    check(not surface.meniscus.status_is_error and len(surface.data.polygons) > 0, surface.meniscus.status)


def test_animation_render_stops_at_a_missing_frame():
    status, output, written, reports = render_saved_copy("STOP", 29, 31)
    check(status == 1, f"exit status {status}; end of output:\n{output[-3000:]}")
    check(written == ["frame_0029.png"], f"images written: {written}")
    check("double_dam_break_0030.vtk" in output and "Missing" in output and "render stopped" in output,
          output[-3000:])
    check("Traceback" not in output, output[-3000:])


def test_broken_frame_stops_the_render_naming_file_and_reason():
    status, output, written, _ = render_saved_copy("STOP", 31)
    check(status == 1 and written == [], f"exit status {status}, images {written}; output:\n{output[-3000:]}")
    message = [line for line in output.splitlines() if "cannot be built for frame 31" in line]
    check(len(message) == 1 and BROKEN in message[0], f"no one line naming the file: {output[-3000:]}")
    # The reason, beyond the file's name: what the reader found wrong with it.
    check(len(message[0].split(BROKEN, 1)[1].strip(" :")) > 10, message[0])


def test_hold_last_good_frame_renders_the_nearest_earlier_file():
    status, output, written, reports = render_saved_copy("HOLD", 31)
    check(status == 0 and written == ["frame_0031.png"], f"exit status {status}, images {written}:\n{output[-3000:]}")
    # 31 is broken and 30 missing: the nearest earlier frame that builds is 29.
    check(len(reports) == 1 and reports[0].startswith("Holding double_dam_break_0029.vtk") and
          int(reports[0].rsplit(" ", 1)[1]) > 0, reports)


def test_empty_surface_renders_the_frame_without_it():
    status, output, written, reports = render_saved_copy("EMPTY", 30)
    check(status == 0 and written == ["frame_0030.png"], f"exit status {status}, images {written}:\n{output[-3000:]}")
    check(len(reports) == 1 and "double_dam_break_0030.vtk" in reports[0] and reports[0].endswith(" 0"), reports)


def test_interactive_render_sets_the_failed_frames_image_aside():
    # Blender cannot be stopped from an interactive render: what it does there is called directly (this process has
    # no UI, where stop_render exits). The image of the failed frame is renamed once written; others stay.
    render_policy, app_handlers = _support.addon_modules(addon, "blender.render_policy", "blender.app_handlers")
    app_handlers.meniscus_render_init(scene)
    render_policy.report_unstoppable_failure("Meniscus: surface 'x' cannot be built for frame 30: test", 30)
    written = {}
    for frame in (29, 30):
        scene.frame_current = frame
        path = bpy.path.abspath(scene.render.frame_path(frame=frame))
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as image:
            image.write(b"rendered without the surface" if frame == 30 else b"a good frame")
        app_handlers.meniscus_render_write(scene)
        written[frame] = path
    check(os.path.exists(written[29]), "a good frame's image was moved")
    check(not os.path.exists(written[30]), f"the failed frame's image stays as if fine: {written[30]}")
    check(os.path.exists(written[30].replace(".png", ".meniscus-failed.png")), os.listdir(os.path.dirname(written[30])))


def test_failed_frames_image_held_open_by_a_viewer():
    # A viewer holding the new image open without delete sharing (Python's open shares none): Windows refuses the
    # rename while it does, and the add-on waits for it (busy_files); held throughout, the console names the image and
    # the time waited, and the image keeps its name. Elsewhere the rename is not refused.
    render_policy, app_handlers, busy_files = _support.addon_modules(
        addon, "blender.render_policy", "blender.app_handlers", "busy_files")
    app_handlers.meniscus_render_init(scene)
    render_policy.report_unstoppable_failure("Meniscus: surface 'x' cannot be built for frame 32: test", 32)
    scene.frame_current = 32
    path = bpy.path.abspath(scene.render.frame_path(frame=32))
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as image:
        image.write(b"rendered without the surface")
    printed, wait = io.StringIO(), busy_files.WAIT_SECONDS
    busy_files.WAIT_SECONDS = 0.3
    try:
        with open(path, "rb"), contextlib.redirect_stdout(printed):
            app_handlers.meniscus_render_write(scene)
    finally:
        busy_files.WAIT_SECONDS = wait
    set_aside = path.replace(".png", ".meniscus-failed.png")
    if os.name == "nt":
        check(os.path.exists(path) and not os.path.exists(set_aside), os.listdir(os.path.dirname(path)))
        check(f"its image {path} could not be renamed" in printed.getvalue() and "waited 0.3 s" in printed.getvalue(),
              printed.getvalue())
    else:
        check(not os.path.exists(path) and os.path.exists(set_aside), os.listdir(os.path.dirname(path)))


def test_interactive_stereo_render_sets_each_views_image_aside():
    # Views written as individual images (frame_0030_L.png, frame_0030_R.png): each one of the failed frame is renamed.
    render_policy, app_handlers = _support.addon_modules(addon, "blender.render_policy", "blender.app_handlers")
    render = scene.render
    render.use_multiview, render.image_settings.views_format = True, "INDIVIDUAL"
    try:
        app_handlers.meniscus_render_init(scene)
        render_policy.report_unstoppable_failure("Meniscus: surface 'x' cannot be built for frame 31: test", 31)
        scene.frame_current = 31
        paths = [bpy.path.abspath(render.frame_path(frame=31, view=view.name)) for view in render.views if view.use]
        check(len(paths) == 2 and len(set(paths)) == 2, paths)
        for path in paths:
            os.makedirs(os.path.dirname(path), exist_ok=True)
            with open(path, "wb") as image:
                image.write(b"rendered without the surface")
        app_handlers.meniscus_render_write(scene)
        for path in paths:
            check(not os.path.exists(path), f"a view's image of the failed frame stays as if fine: {path}")
            root, extension = os.path.splitext(path)
            check(os.path.exists(root + ".meniscus-failed" + extension), os.listdir(os.path.dirname(path)))
    finally:
        render.use_multiview = False

_support.run(globals(), cleanup=addon.unregister)
