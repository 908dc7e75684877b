"""Whether a final render is running: surfaces use their render cube size meanwhile.

A flag of our own, set between render_init and render_complete/render_cancel, because
bpy.app.is_job_running('RENDER') is False for renders from the command line (`blender -b -a` runs no
window-manager job), where the render parameters matter just as much.
"""
import bpy

_render_in_progress = False


def set_rendering(active):
    global _render_in_progress
    _render_in_progress = bool(active)


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
