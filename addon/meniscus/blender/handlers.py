"""Rebuilding surfaces on frame change, and keeping the handlers registered across file loads.

Rules the handler lives by (it runs inside Blender's frame change, also on the render thread):
- it never raises: an exception would print a traceback on every frame, or abort a render. Errors go to the
  object's status line and the mesh is left empty for that frame;
- it touches only data (no operators, no bpy.context), because during a render it runs beside the UI;
- it leaves objects in Edit Mode alone: replacing the geometry under an open BMesh loses the edit or worse;
- it skips the rebuild when the file and parameters are those already shown, which makes motion-blur subframes and
  repeated depsgraph updates free.
"""
import os
import time
import traceback

import bpy
from bpy.app.handlers import persistent

from .. import api, sequence
from . import mesh_update

STATUS_LINE_SEPARATOR = "\n"

# Names under which particle velocities appear in the formats we read (VTK writers, Houdini's 'v').
_VELOCITY_NAMES = ("velocity", "v", "vel", "Velocity")

# Folder listings and parsed patterns, shared by all surfaces.
_sequences = sequence.SequenceCache()
# What each mesh currently shows: mesh pointer -> (rebuild key, vertex count). The vertex count guards against a
# pointer reused by a new mesh and against geometry changed behind our back.
_shown = {}
# Last error message per mesh pointer: the traceback is printed once, not on every frame.
_last_error = {}


class SurfaceError(Exception):
    """A problem the user can fix (bad pattern, missing file): reported without a traceback."""


def is_surface(obj):
    return obj is not None and obj.type == "MESH" and obj.meniscus.is_surface


def surface_objects(scene):
    return [obj for obj in scene.objects if is_surface(obj)]


def forget_cached_state():
    """Drops listings and the record of what meshes show, so the next update re-reads everything."""
    _sequences.clear()
    _shown.clear()
    _last_error.clear()


def resolve_pattern(obj):
    """The parsed absolute frame pattern of a surface object; raises SurfaceError when it cannot be used."""
    settings = obj.meniscus
    if not settings.file_pattern:
        raise SurfaceError("No particle files set")
    # Relative paths ('//') are kept in the property and resolved against the .blend (or its library) only here.
    absolute = bpy.path.abspath(settings.file_pattern, library=obj.library)
    try:
        return _sequences.pattern(os.path.normpath(absolute))
    except ValueError as error:
        raise SurfaceError(str(error)) from None


def available_frames(obj):
    """Frame number -> path of the files of a surface's sequence (cached; re-listed when the folder changes)."""
    return _sequences.frames(resolve_pattern(obj))


def _rebuild_key(settings, lookup):
    # Everything the mesh depends on: the file (and its version on disk) and every reconstruction parameter.
    try:
        stat = os.stat(lookup.path) if lookup.path else None
        file_version = (stat.st_mtime_ns, stat.st_size) if stat else None
    except OSError:
        file_version = None
    return (lookup.file_frame, lookup.path, file_version, settings.particle_radius, settings.smoothing_length,
            settings.cube_size, settings.iso_threshold, settings.smoothing_iterations, settings.decimate_barnacles,
            settings.normal_smoothing_iterations, settings.use_custom_normals)


def _set_status(settings, text, is_error=False):
    # Writing an unchanged value would still tag the object for redraw/undo; skip it.
    if settings.status != text:
        settings.status = text
    if settings.status_is_error != is_error:
        settings.status_is_error = is_error


def _find_velocity(attributes, particle_count):
    for name in _VELOCITY_NAMES:
        values = attributes.get(name)
        if values is not None and getattr(values, "shape", None) == (particle_count, 3):
            return values
    return None


def _reconstruct_into(mesh, settings, path):
    """Reads one particle file, reconstructs it and writes the mesh. Returns the status line."""
    started = time.perf_counter()
    particles = api.read_particles(path)
    velocity = _find_velocity(particles.attributes, len(particles))
    surface = api.reconstruct(
        particles.positions,
        particle_radius=settings.particle_radius,
        smoothing_length=settings.smoothing_length,
        cube_size=settings.cube_size,
        iso_threshold=settings.iso_threshold,
        attributes={"velocity": velocity} if velocity is not None else None,
        decimate_barnacles=settings.decimate_barnacles,
        smoothing_iterations=settings.smoothing_iterations,
        normal_smoothing_iterations=settings.normal_smoothing_iterations,
        normals=settings.use_custom_normals,
    )
    reconstructed = time.perf_counter()

    point_vectors = {}
    surface_velocity = surface.attributes.get("velocity")
    if surface_velocity is not None:
        point_vectors[mesh_update.VELOCITY_ATTRIBUTE] = surface_velocity
    normals = surface.normals if settings.use_custom_normals else None
    mesh_update.write_surface(mesh, surface.vertices, surface.triangles, normals, point_vectors)
    finished = time.perf_counter()

    # One fact per line: the panel shows each on its own row, where a narrow sidebar would cut a single long line.
    return STATUS_LINE_SEPARATOR.join((
        os.path.basename(path),
        f"{len(particles):,} particles",
        f"{len(surface.triangles):,} triangles",
        f"{reconstructed - started:.2f} s + {finished - reconstructed:.2f} s in Blender",
    ))


def update_surface(obj, scene, force=False):
    """Makes a surface object show the file of the scene's current frame. Never raises.

    Returns True when the mesh was rebuilt (or emptied), False when nothing had to be done or it was skipped.
    """
    try:
        settings = obj.meniscus
        mesh = obj.data
        if obj.mode == "EDIT" or mesh.is_editmode:
            return False
        pointer = mesh.as_pointer()
        name, frame = obj.name, scene.frame_current
        # Fractional during motion-blur shutter steps; the sequence module rounds it to the nearest file frame.
        scene_time = frame + scene.frame_subframe
    except Exception:  # the object or its mesh was removed while we held a reference
        return False

    key = None
    try:
        pattern = resolve_pattern(obj)
        frames = _sequences.frames(pattern)
        try:
            lookup = sequence.lookup_frame(frames, pattern, scene_time, settings.frame_offset,
                                           settings.frame_start, settings.frame_end, settings.out_of_range)
        except ValueError as error:
            raise SurfaceError(str(error)) from None

        key = _rebuild_key(settings, lookup)
        if not force and _shown.get(pointer) == (key, len(mesh.vertices)):
            return False
        # Recorded before the work so that a failing file is not retried on every subframe of the same frame.
        _shown[pointer] = (key, -1)

        if lookup.file_frame is None:
            mesh_update.clear_surface(mesh)
            _set_status(settings, f"Frame {frame}: outside the range, blank")
        elif lookup.path is None:
            mesh_update.clear_surface(mesh)
            _set_status(settings, f"Missing file: {lookup.expected_path}", is_error=True)
        else:
            _set_status(settings, _reconstruct_into(mesh, settings, lookup.path))
        _shown[pointer] = (key, len(mesh.vertices))
        _last_error.pop(pointer, None)
        return True
    except Exception as error:
        message = str(error) or type(error).__name__
        # Unreadable files are the user's to fix and the message names file and fault: no traceback for those.
        # MemoryError carries the core's estimate of the grid it refused to allocate: a parameter to change too.
        expected = isinstance(error, (SurfaceError, api.FormatError, OSError, MemoryError))
        if _last_error.get(pointer) != message:  # once per distinct problem, not on every frame
            print(f"Meniscus: '{name}' at frame {frame}: {message}")
            if not expected:
                traceback.print_exc()
        _last_error[pointer] = message
        try:
            mesh_update.clear_surface(mesh)
            if key is None:  # failed before knowing what to show: nothing to remember, try again next time
                _shown.pop(pointer, None)
            else:
                _shown[pointer] = (key, len(mesh.vertices))
            _set_status(settings, message if expected else f"Error: {message}", is_error=True)
        except Exception:
            traceback.print_exc()
        return True


def update_scene(scene, force=False):
    """Updates every surface object of a scene; returns how many meshes were rebuilt."""
    rebuilt = 0
    for obj in surface_objects(scene):
        rebuilt += bool(update_surface(obj, scene, force))
    return rebuilt


@persistent
def meniscus_frame_change_post(scene, depsgraph=None):
    try:
        update_scene(scene)
    except Exception:  # update_surface never raises; this guards the loop itself (e.g. a scene being freed)
        traceback.print_exc()


@persistent
def meniscus_load_post(*_args):
    # A new file means new meshes: pointers and listings of the previous file mean nothing any more.
    forget_cached_state()
    _append_once(bpy.app.handlers.frame_change_post, meniscus_frame_change_post)
    try:
        scene = bpy.context.scene
        if scene is not None:
            update_scene(scene)
    except Exception:
        traceback.print_exc()


@persistent
def meniscus_undo_redo_post(*_args):
    # Undo restores parameters, the frame and the meshes as the undo step saved them, which normally agree; the
    # usual check of file and parameters against what each mesh shows (a rebuild only on a mismatch, e.g. a mesh
    # that undo moved in memory) guards the cases where they do not.
    try:
        scene = bpy.context.scene
        if scene is not None:
            update_scene(scene)
    except Exception:
        traceback.print_exc()


def _remove_ours(handler_list, function):
    # Matching by name and module (not identity) also removes the copy left by a previous import of this module,
    # e.g. after the add-on was reloaded without unregistering.
    for existing in list(handler_list):
        if getattr(existing, "__name__", None) == function.__name__ and \
                getattr(existing, "__module__", None) == function.__module__:
            handler_list.remove(existing)


def _append_once(handler_list, function):
    _remove_ours(handler_list, function)
    handler_list.append(function)


def ensure_registered():
    """Makes sure the frame handler is installed exactly once (called by the add operator and load_post)."""
    _append_once(bpy.app.handlers.frame_change_post, meniscus_frame_change_post)


def _handler_slots():
    handlers = bpy.app.handlers
    return ((handlers.frame_change_post, meniscus_frame_change_post),
            (handlers.load_post, meniscus_load_post),
            (handlers.undo_post, meniscus_undo_redo_post),
            (handlers.redo_post, meniscus_undo_redo_post))


def register():
    for handler_list, function in _handler_slots():
        _append_once(handler_list, function)


def unregister():
    for handler_list, function in _handler_slots():
        _remove_ours(handler_list, function)
    forget_cached_state()
