"""What a final render does with a frame whose surface cannot be built (a missing or broken particle file, a render
cube size refused for memory, a parameter out of range): the surface setting "If a Frame Fails".

- STOP (default): the render stops. From the command line or a farm (`blender -b scene.blend -f 22`, `-a`) the
  Blender process exits with status 1 after printing which surface, frame and file failed and why, so a farm marks
  the frame failed instead of accepting an image without water. In an interactive session Blender offers Python no
  way to cancel its render job (3.4 to 5.2 have no operator or function for it; Esc is the user's): the error goes
  to the status line, the console and a message box, the surface renders empty, and an animation render's image of
  that frame is renamed once written (frame_0030.png -> frame_0030.meniscus-failed.png), so that the sequence has a
  gap where the frame failed instead of an image that looks fine.
- HOLD: the nearest earlier frame of the sequence that builds is shown instead (found the same way on every farm
  node, whatever it rendered before); when none of the few tried builds, the render stops as with STOP.
- EMPTY: the frame renders without the surface, as the viewport shows it; the problem is printed.
The viewport is never affected: there a failed frame shows an empty mesh and the error in the status line.
"""
import os
import sys

import bpy

from .. import busy_files

STOP, HOLD, EMPTY = "STOP", "HOLD", "EMPTY"
ITEMS = [
    (STOP, "Stop the Render", "Stop the render with an error (command line and farms: Blender exits with status 1), "
                              "naming the file and the reason"),
    (HOLD, "Hold Last Good Frame", "Render the nearest earlier frame that can be built instead"),
    (EMPTY, "Empty Surface", "Render the frame without the surface and go on"),
]
# Earlier frames HOLD tries before it gives up: bounded, because a problem that is not the file's (memory, a
# parameter) fails at every frame and each try costs a reconstruction.
HOLD_TRIES = 3
EXIT_STATUS = 1
# What a failed frame's image is renamed to in an interactive render (inserted before the file's extension).
FAILED_IMAGE_MARK = ".meniscus-failed"
# Frames of the running interactive render that failed under STOP, whose image must not stay as if fine.
_failed_frames = set()


def failure_message(object_name, frame, source, reason):
    """One line naming what failed, where, and why (the path once, even when the reason already names it)."""
    where = reason if source and source in reason else f"{source}: {reason}" if source else reason
    return f"Meniscus: surface '{object_name}' cannot be built for frame {frame}: {where}"


def earlier_frames(frames, failed_frame):
    """The file frames HOLD tries, nearest first: those listed before the failed one."""
    candidates = sorted((frame for frame in frames if failed_frame is None or frame < failed_frame), reverse=True)
    return candidates[:HOLD_TRIES]


def stop_render(message, frame):
    """Ends a final render that must not go on. Without a UI the process exits now with EXIT_STATUS (a handler's
    exception would only be printed and the frame written); with a UI the user is told at once and the frame's
    image is set aside when it is written (set_aside_failed_image)."""
    text = f"{message}\nMeniscus: render stopped (the surface setting 'If a Frame Fails' can hold the last good " \
           f"frame or render an empty surface instead)"
    print(text, file=sys.stderr)
    if bpy.app.background:
        sys.stdout.flush()
        sys.stderr.flush()
        # Exiting here, not raising: Blender prints a handler's exception and renders the frame anyway.
        os._exit(EXIT_STATUS)
    report_unstoppable_failure(message, frame)


def report_unstoppable_failure(message, frame):
    """An interactive render goes on: the user is told at once and the frame's image will be set aside."""
    _failed_frames.add(frame)
    _show_message_box(message)


def set_aside_failed_image(scene):
    """After an interactive render wrote a frame (render_write): renames the image of a frame that failed under STOP
    to <name>.meniscus-failed<ext> (each view's image of a stereo render written as individual views), so that
    nothing downstream takes it for a good frame (a movie file cannot be changed: the message stays the only sign).
    Returns the new paths (empty when nothing was renamed)."""
    frame = scene.frame_current
    if frame not in _failed_frames:
        return []
    _failed_frames.discard(frame)
    render = scene.render
    if render.is_movie_format:
        print(f"Meniscus: frame {frame} of the movie renders without the surface (see the error above)")
        return []
    if render.use_multiview and render.image_settings.views_format == "INDIVIDUAL":  # frame_0030_L.png, _R.png
        paths = [render.frame_path(frame=frame, view=view.name) for view in render.views if view.use]
    else:
        paths = [render.frame_path(frame=frame)]
    renamed = []
    for path in map(bpy.path.abspath, paths):
        root, extension = os.path.splitext(path)
        failed_path = root + FAILED_IMAGE_MARK + extension
        try:
            busy_files.replace(path, failed_path)  # an image viewer may have the new image open for a moment
        except OSError as error:
            print(f"Meniscus: frame {frame} rendered without the surface, and its image {path} could not be renamed "
                  f"to {failed_path} ({error.strerror or error}): do not use it")
            continue
        print(f"Meniscus: frame {frame} rendered without the surface; its image was renamed to {failed_path}")
        renamed.append(failed_path)
    return renamed


def forget_failed_frames():
    """A render ended: frames that failed in it are not this next render's."""
    _failed_frames.clear()


def _show_message_box(message):
    def draw(menu, _context):
        menu.layout.label(text=message)

    def show():  # on the main thread: this may run on the render thread
        try:
            bpy.context.window_manager.popup_menu(draw, title="Meniscus: render frame failed", icon="ERROR")
        except Exception:  # no window to show it in: the console and the status line have it
            pass
        return None

    bpy.app.timers.register(show, first_interval=0.0)
