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

from .. import api, cache, sequence
from . import mesh_update, sources

STATUS_LINE_SEPARATOR = "\n"

# Folder listings and parsed patterns, shared by all surfaces (particle files and caches alike).
_sequences = sequence.SequenceCache()
# What each mesh currently shows: mesh pointer -> (rebuild key, vertex count). The vertex count guards against a
# pointer reused by a new mesh and against geometry changed behind our back.
_shown = {}
# Last error message per mesh pointer: the traceback is printed once, not on every frame.
_last_error = {}
# Set between render_init and render_complete/render_cancel: surfaces use their render cube size meanwhile.
# A flag of our own because bpy.app.is_job_running('RENDER') is False for renders from the command line
# (`blender -b -a` runs no window-manager job), where the render parameters matter just as much.
_render_in_progress = False


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


def _resolve(path_property, obj, what):
    if not path_property:
        raise SurfaceError(f"No {what} set")
    # Relative paths ('//') are kept in the property and resolved against the .blend (or its library) only here.
    absolute = bpy.path.abspath(path_property, library=obj.library)
    try:
        return _sequences.pattern(os.path.normpath(absolute))
    except ValueError as error:
        raise SurfaceError(str(error)) from None


def resolve_pattern(obj):
    """The parsed absolute frame pattern of a surface's particle files; raises SurfaceError when unusable."""
    return _resolve(obj.meniscus.file_pattern, obj, "particle files")


def cache_pattern_string(obj):
    """The cache pattern as stored (possibly '//'-relative): the chosen one or the default next to the .blend."""
    settings = obj.meniscus
    return settings.cache_pattern or cache.default_cache_pattern(obj.name, settings.cache_format)


def resolve_cache_pattern(obj):
    if not obj.meniscus.cache_pattern and not bpy.data.is_saved:
        raise SurfaceError("No cache folder set (save the .blend or choose Cache Files)")
    return _resolve(cache_pattern_string(obj), obj, "cache files")


def available_frames(obj):
    """Frame number -> path of the files of a surface's sequence (cached; re-listed when the folder changes)."""
    return _sequences.frames(resolve_pattern(obj))


def available_cache_frames(obj):
    return _sequences.frames(resolve_cache_pattern(obj))


def reconstruction_arguments(settings, for_render, normals=None):
    """api.reconstruct's keyword arguments from a surface's settings (render or viewport cube size)."""
    return dict(
        particle_radius=settings.particle_radius,
        smoothing_length=settings.smoothing_length,
        cube_size=settings.render_cube_size if for_render else settings.cube_size,
        iso_threshold=settings.iso_threshold,
        mesh_cleanup=settings.mesh_cleanup,
        # The core's convention: a negative distance snaps every vertex.
        mesh_cleanup_snap_distance=settings.mesh_cleanup_snap_distance if settings.use_snap_distance else -1.0,
        decimate_barnacles=settings.decimate_barnacles,
        smoothing_iterations=settings.smoothing_iterations,
        smoothing_beta=settings.smoothing_strength,
        smoothing_weights=settings.use_feature_weights,
        weights_normalization=0.0 if settings.weights_normalization_auto else settings.weights_normalization,
        volume_restoration=settings.volume_restoration,
        output_weights=settings.output_weights,
        normals=settings.use_custom_normals if normals is None else normals,
        normal_smoothing_iterations=settings.normal_smoothing_iterations,
        sph_normals=settings.sph_normals,
        threads=settings.threads,
        memory_budget=settings.memory_budget_mb * 1024 * 1024,
    )


def _file_version(path):
    try:
        stat = os.stat(path) if path else None
        return (stat.st_mtime_ns, stat.st_size) if stat else None
    except OSError:
        return None


def _set_status(settings, text, is_error=False):
    # Writing an unchanged value would still tag the object for redraw/undo; skip it.
    if settings.status != text:
        settings.status = text
    if settings.status_is_error != is_error:
        settings.status_is_error = is_error


def _write(mesh, settings, surface):
    """Writes a reconstructed or loaded surface into the Blender mesh; returns the seconds it took and a status
    note on attributes stored under another name or not at all (the user must find what they asked for)."""
    started = time.perf_counter()
    normals = surface.normals if settings.use_custom_normals else None
    elsewhere = mesh_update.write_surface(mesh, surface.vertices, surface.triangles, normals, surface.attributes)
    notes = [f"'{name}' stored as '{stored}'" if stored else f"'{name}' not stored (no Blender type for its shape)"
             for name, stored in sorted(elsewhere.items())]
    return time.perf_counter() - started, "; ".join(notes)


def _status_lines(*lines):
    # One fact per line: the panel shows each on its own row, where a narrow sidebar would cut a single long line.
    return STATUS_LINE_SEPARATOR.join(line for line in lines if line)


def _missing_note(result):
    return f"not in the particles: {', '.join(result.missing_attributes)}" if result.missing_attributes else ""


# Sources: each returns (rebuild key, work) where work() fills the mesh and returns the status text -------------

def _file_source(obj, settings, mesh, scene_time, for_render):
    pattern = resolve_pattern(obj)
    lookup = _lookup(_sequences.frames(pattern), pattern, scene_time, settings)
    arguments = reconstruction_arguments(settings, for_render)
    wanted = cache.parse_attribute_names(settings.attribute_names)
    # Everything the mesh depends on: the file (and its version on disk) and every reconstruction parameter.
    key = ("FILES", lookup.file_frame, lookup.path, _file_version(lookup.path), tuple(sorted(arguments.items())),
           tuple(wanted), settings.use_custom_normals)

    def work():
        if lookup.path is None:
            return _empty_for(mesh, lookup, scene_time, "file")
        result = cache.reconstruct_file(lookup.path, arguments, wanted)
        blender_seconds, attribute_note = _write(mesh, settings, result.mesh)
        return _status_lines(
            os.path.basename(lookup.path) + (" (render)" if for_render else ""),
            f"{result.particle_count:,} particles",
            f"{len(result.mesh.triangles):,} triangles",
            f"{result.seconds:.2f} s + {blender_seconds:.2f} s in Blender",
            _missing_note(result), attribute_note)

    return key, work


def _cache_source(obj, settings, mesh, scene_time):
    pattern = resolve_cache_pattern(obj)
    lookup = _lookup(_sequences.frames(pattern), pattern, scene_time, settings)
    key = ("CACHE", lookup.file_frame, lookup.path, _file_version(lookup.path), settings.use_custom_normals)

    def work():
        if lookup.path is None:
            return _empty_for(mesh, lookup, scene_time, "baked frame")
        started = time.perf_counter()
        surface = cache.load_mesh(lookup.path)
        loaded = time.perf_counter() - started
        blender_seconds, attribute_note = _write(mesh, settings, surface)
        return _status_lines(
            f"{os.path.basename(lookup.path)} (cache)",
            f"{len(surface.triangles):,} triangles",
            f"{loaded:.2f} s loading + {blender_seconds:.2f} s in Blender", attribute_note)

    return key, work


def _object_source(obj, settings, mesh, depsgraph, for_render):
    source = settings.source_object
    if source is None:
        raise SurfaceError("No source object set")
    if source == obj:
        raise SurfaceError("A surface cannot be its own source")
    wanted = cache.parse_attribute_names(settings.attribute_names)
    positions, attributes, kind = sources.object_particles(source, depsgraph, wanted)
    arguments = reconstruction_arguments(settings, for_render)
    # The positions themselves are the key: the source may change without a frame change (an edit, a re-bake).
    key = ("OBJECT", source.name, sources.digest(positions), tuple(sorted(arguments.items())), tuple(wanted),
           settings.use_custom_normals)

    def work():
        result = cache.reconstruct_positions(positions, attributes, arguments, wanted)
        blender_seconds, attribute_note = _write(mesh, settings, result.mesh)
        return _status_lines(
            f"{source.name}: {kind}" + (" (render)" if for_render else ""),
            f"{result.particle_count:,} particles",
            f"{len(result.mesh.triangles):,} triangles",
            f"{result.seconds:.2f} s + {blender_seconds:.2f} s in Blender",
            _missing_note(result), attribute_note)

    return key, work


def _lookup(frames, pattern, scene_time, settings):
    try:
        return sequence.lookup_frame(frames, pattern, scene_time, settings.frame_offset, settings.frame_start,
                                     settings.frame_end, settings.out_of_range)
    except ValueError as error:
        raise SurfaceError(str(error)) from None


class _Blank(Exception):
    """Not an error: the frame is outside the range in BLANK mode."""


def _empty_for(mesh, lookup, scene_time, what):
    mesh_update.clear_surface(mesh)
    if lookup.file_frame is None:
        raise _Blank(f"Frame {sequence.nearest_frame(scene_time)}: outside the range, blank")
    raise SurfaceError(f"Missing {what}: {lookup.expected_path}")


def update_surface(obj, scene, force=False, depsgraph=None):
    """Makes a surface object show the scene's current frame. Never raises.

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
        is_subframe = scene.frame_subframe != 0.0
    except Exception:  # the object or its mesh was removed while we held a reference
        return False

    key = None
    try:
        for_render = is_rendering()
        if settings.use_cache:
            key, work = _cache_source(obj, settings, mesh, scene_time)
        elif settings.source_type == "OBJECT":
            if is_subframe and pointer in _shown and not force:
                # A live simulation moves at every shutter step; one surface per frame is enough (the velocity
                # attribute carries the motion), so subframes keep what the frame built.
                return False
            key, work = _object_source(obj, settings, mesh, depsgraph, for_render)
        else:
            key, work = _file_source(obj, settings, mesh, scene_time, for_render)

        if not force and _shown.get(pointer) == (key, len(mesh.vertices)):
            return False
        # Recorded before the work so that a failing file is not retried on every subframe of the same frame.
        _shown[pointer] = (key, -1)
        try:
            _set_status(settings, work())
        except _Blank as blank:
            _set_status(settings, str(blank))
        _shown[pointer] = (key, len(mesh.vertices))
        _last_error.pop(pointer, None)
        return True
    except Exception as error:
        message = str(error) or type(error).__name__
        # Unreadable files are the user's to fix and the message names file and fault: no traceback for those.
        # MemoryError carries the core's estimate of the grid it refused to allocate: a parameter to change too.
        expected = isinstance(error, (SurfaceError, api.FormatError, OSError, MemoryError))
        if isinstance(error, MemoryError) and not str(error):
            message = "Out of memory: use a larger cube size"
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


def update_scene(scene, force=False, depsgraph=None):
    """Updates every surface object of a scene; returns how many meshes were rebuilt."""
    rebuilt = 0
    for obj in surface_objects(scene):
        rebuilt += bool(update_surface(obj, scene, force, depsgraph))
    return rebuilt


@persistent
def meniscus_frame_change_post(scene, depsgraph=None):
    try:
        update_scene(scene, depsgraph=depsgraph)
    except Exception:  # update_surface never raises; this guards the loop itself (e.g. a scene being freed)
        traceback.print_exc()


@persistent
def meniscus_depsgraph_update_post(scene, depsgraph=None):
    # Live sources change without a frame change too (the user edits the source mesh, a simulation re-bakes):
    # rebuild the surfaces whose source object is among the updated data. Our own mesh writes also land here;
    # they are not sources, and an unchanged source hashes to the same key, so this never loops.
    try:
        if depsgraph is None or is_rendering():
            return
        updated = {update.id.original for update in depsgraph.updates if isinstance(update.id, bpy.types.Object)}
        if not updated:
            return
        for obj in surface_objects(scene):
            settings = obj.meniscus
            if settings.source_type == "OBJECT" and not settings.use_cache and settings.source_object in updated:
                update_surface(obj, scene, depsgraph=depsgraph)
    except Exception:
        traceback.print_exc()


@persistent
def meniscus_render_init(scene, *_args):
    global _render_in_progress
    _render_in_progress = True


@persistent
def meniscus_render_pre(scene, *_args):
    # A still render (F12) does not change the frame, so the surface still has the viewport cube size: rebuild it
    # with the render settings here, before the render evaluates the scene. In an animation render the frame
    # change has already done so and this finds nothing to do.
    try:
        update_scene(scene)
    except Exception:
        traceback.print_exc()


@persistent
def meniscus_render_done(scene, *_args):
    global _render_in_progress
    _render_in_progress = False
    if bpy.app.background:  # no viewport to restore; the next frame change uses the viewport settings anyway
        return
    # Back to viewport resolution, but on the main thread (this handler may run on the render thread).
    scene_name = scene.name

    def restore_viewport_surfaces():
        try:
            target = bpy.data.scenes.get(scene_name)
            if target is not None:
                update_scene(target)
        except Exception:
            traceback.print_exc()
        return None  # once

    bpy.app.timers.register(restore_viewport_surfaces, first_interval=0.1)


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
            (handlers.depsgraph_update_post, meniscus_depsgraph_update_post),
            (handlers.render_init, meniscus_render_init),
            (handlers.render_pre, meniscus_render_pre),
            (handlers.render_complete, meniscus_render_done),
            (handlers.render_cancel, meniscus_render_done),
            (handlers.load_post, meniscus_load_post),
            (handlers.undo_post, meniscus_undo_redo_post),
            (handlers.redo_post, meniscus_undo_redo_post))


def register():
    for handler_list, function in _handler_slots():
        _append_once(handler_list, function)


def unregister():
    global _render_in_progress
    for handler_list, function in _handler_slots():
        _remove_ours(handler_list, function)
    forget_cached_state()
    _render_in_progress = False
