"""Animation render: the frame handler runs inside the render job for every frame (and shutter subframe), and while a
frame renders the worker builds the next one (build-ahead), which the next frame change takes ready; the images are
those of a render without build-ahead."""
import os
import sys
import tempfile
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
update, render_state = _support.addon_modules(addon, "blender.update", "blender.render_state")
_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()
surface.meniscus.cube_size = 1.0  # coarse and unsmoothed: this test is about the render path, not the surface
surface.meniscus.smoothing_iterations = 0
surface.meniscus.render_cube_size = 1.0
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_anim_")


def test_animation_render_with_motion_blur():
    scene.render.use_motion_blur = True
    scene.frame_start, scene.frame_end = 29, 31
    # What the surface showed when each frame was written (the render restores the scene frame afterwards).
    shown = []

    def record(_scene, _depsgraph=None):
        shown.append((surface.meniscus.status.splitlines()[0], len(surface.data.polygons)))

    built_ahead_before = update._memory.frames_built_ahead
    bpy.app.handlers.render_write.append(record)
    try:
        with tempfile.TemporaryDirectory(prefix="meniscus_anim_") as folder:
            _support.make_small_render(scene, os.path.join(folder, "frame_####"))
            bpy.ops.render.render(animation=True)
            written = sorted(os.listdir(folder))
            check(written == ["frame_0029.png", "frame_0030.png", "frame_0031.png"], written)
    finally:
        bpy.app.handlers.render_write.remove(record)
    files = [name for name, _ in shown]
    # '(render)': the handler knew a render was running and used the render cube size; the frames after the first
    # were built by the worker while the one before rendered.
    check(files == ["double_dam_break_0029.vtk (render)"] +
          [f"double_dam_break_00{frame}.vtk (render, built ahead)" for frame in (30, 31)], f"rendered files: {shown}")
    check(update._memory.frames_built_ahead - built_ahead_before == 2, update._memory.frames_built_ahead)
    check(all(triangles > 0 for _, triangles in shown), f"empty surface in a rendered frame: {shown}")
    check(not surface.meniscus.status_is_error, surface.meniscus.status)



def test_render_end_drops_the_next_frame_not_yet_started():
    # A render cancelled (or ended) while the worker still had the next frame queued: that work is dropped, not
    # built for nobody. The worker is held on another job so that the frame stays queued.
    import threading
    playback = sys.modules[type(update._prefetcher).__module__]
    app_handlers = _support.addon_modules(addon, "blender.app_handlers")
    release = threading.Event()
    blocker = playback.FrameCache(1 << 20)
    scene.frame_start, scene.frame_end = 29, 31
    frame_before = scene.frame_current
    scene.frame_set(29)
    # The viewport's own prefetch of frames 30-32 finished and dropped, so that frame 30 is not already there.
    deadline = time.monotonic() + 60
    while not update._prefetcher.idle() and time.monotonic() < deadline:
        time.sleep(0.05)
    update._memory.frame_cache(surface.data.as_pointer()).clear()
    render_state.set_rendering(True)
    try:
        update._prefetcher.want(blocker, [("hold the worker", lambda: release.wait(30) and None)])
        update.build_next_render_frame(scene)
        queued = [slot for slot in update._prefetcher._wanted if slot[0] != id(blocker)]
        check(len(queued) == 1, f"frame 30 not queued: {list(update._prefetcher._wanted)}")
        app_handlers.meniscus_render_done(scene)
        left = [slot for slot in update._prefetcher._wanted if slot[0] != id(blocker)]
        check(left == [], f"still queued after the render ended: {left}")
    finally:
        release.set()
        render_state.set_rendering(False)
        scene.frame_set(frame_before)  # the saved copies of the next test start where they did

def _render_saved_copy(name, build_ahead):
    """Renders frames 29-31 of a saved copy in a new process, as a farm node does; returns (the surface's status
    line and face count per frame, the images' pixels)."""
    blend = os.path.join(_temporary.name, "scene.blend")
    out = os.path.join(_temporary.name, name)
    _support.make_small_render(scene, os.path.join(out, "frame_####"))
    scene.render.use_motion_blur = False
    bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True)
    completed = _support.render_in_new_process(
        blend, 29, 31, report=f"bpy.data.objects[{surface.name!r}]",
        environment={render_state.BUILD_AHEAD_VARIABLE: "1" if build_ahead else "0"})
    check(completed.returncode == 0, completed.stdout[-3000:])
    reports = [line.split(" ", 1)[1] for line in completed.stdout.splitlines() if line.startswith("RENDERED ")]
    images = []
    for file_name in sorted(os.listdir(out)):
        image = bpy.data.images.load(os.path.join(out, file_name))
        images.append(np.array(image.pixels[:]))
        bpy.data.images.remove(image)
    return reports, images


def test_build_ahead_renders_the_same_images_from_the_command_line():
    reports, images = _render_saved_copy("ahead", build_ahead=True)
    plain_reports, plain_images = _render_saved_copy("plain", build_ahead=False)
    check([report.split(" ", 1)[0] for report in reports] == [f"double_dam_break_00{frame}.vtk" for frame in
                                                               (29, 30, 31)], reports)
    check(["built ahead" in report for report in reports] == [False, True, True], reports)
    check(not any("built ahead" in report for report in plain_reports), plain_reports)
    # The same meshes (face counts) and the same pixels: building ahead changes when a frame is built, not what.
    check([report.rsplit(" ", 1)[1] for report in reports] == [report.rsplit(" ", 1)[1] for report in plain_reports],
          f"{reports} against {plain_reports}")
    check(len(images) == 3 and all(np.array_equal(a, b) for a, b in zip(images, plain_images)),
          "images differ with build-ahead")


_support.run(globals(), cleanup=addon.unregister)
