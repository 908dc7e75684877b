"""Whether a final render is running: surfaces use their render cube size meanwhile.

A flag of our own, set between render_init and render_complete/render_cancel, because
bpy.app.is_job_running('RENDER') is False for renders from the command line (`blender -b -a` runs no
window-manager job), where the render parameters matter just as much.
"""
import os
import sys

import bpy

# "0" turns off building the next frame while a frame renders (it holds a second render-size surface in memory and
# shares the CPU with a CPU renderer): MENISCUS_RENDER_BUILD_AHEAD=0 blender -b scene.blend -a
BUILD_AHEAD_VARIABLE = "MENISCUS_RENDER_BUILD_AHEAD"

_render_in_progress = False
# Frames the current render has written (render_write): in the UI only an animation writes frames, so it tells an
# animation from a still render (F12), which may change the frame too but never needs the next one.
_frames_written = 0


def set_rendering(active):
    global _render_in_progress, _frames_written
    _render_in_progress = bool(active)
    _frames_written = 0


def note_frame_written():
    global _frames_written
    _frames_written += 1


def is_rendering():
    """True while a final render (still or animation, UI or command line) is in progress."""
    if _render_in_progress:
        return True
    is_job_running = getattr(bpy.app, "is_job_running", None)  # 3.3+
    if is_job_running is not None:
        try:
            return bool(is_job_running("RENDER"))
        except Exception:
            pass
    return False


def renders_more_frames():
    """Whether a frame change inside a render may be followed by more frames of the same render, so that building
    the next one ahead is worth it. `blender -b scene.blend -f 30` changes the frame as an animation of one frame,
    which only its command line tells apart; in the UI a still render (F12) is told apart by writing no frame."""
    if os.environ.get(BUILD_AHEAD_VARIABLE, "1").strip() == "0":
        return False
    if not bpy.app.background:  # the UI: an animation from its second frame on (it has written one)
        return _frames_written > 0
    if not bpy.app.binary_path:  # the bpy module driven by a script
        return True
    arguments = sys.argv[:sys.argv.index("--")] if "--" in sys.argv else sys.argv
    renders_animation = "-a" in arguments or "--render-anim" in arguments
    renders_frames = "-f" in arguments or "--render-frame" in arguments
    return renders_animation or not renders_frames
