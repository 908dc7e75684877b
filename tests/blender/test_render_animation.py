"""Animation render: the frame handler runs inside the render job for every frame (and shutter subframe)."""
import os
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()
surface.meniscus.cube_size = 1.0  # coarse and unsmoothed: this test is about the render path, not the surface
surface.meniscus.smoothing_iterations = 0
surface.meniscus.render_cube_size = 1.0


def test_animation_render_with_motion_blur():
    scene.render.use_motion_blur = True
    scene.frame_start, scene.frame_end = 29, 31
    # What the surface showed when each frame was written (the render restores the scene frame afterwards).
    shown = []

    def record(_scene, _depsgraph=None):
        shown.append((surface.meniscus.status.splitlines()[0], len(surface.data.polygons)))

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
    # '(render)': the handler knew a render was running and used the render cube size.
    check(files == [f"double_dam_break_00{frame}.vtk (render)" for frame in (29, 30, 31)], f"rendered files: {shown}")
    check(all(triangles > 0 for _, triangles in shown), f"empty surface in a rendered frame: {shown}")
    check(not surface.meniscus.status_is_error, surface.meniscus.status)


_support.run(globals(), cleanup=addon.unregister)
