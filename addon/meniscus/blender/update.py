"""Rebuilding a surface's mesh for the current frame: from particle files, a mesh cache or another object.

Rules the update lives by (it runs inside Blender's frame change, also on the render thread):
- it never raises: an exception would print a traceback on every frame, or abort a render. Errors go to the
  object's status line and the mesh is left empty for that frame;
- it touches only data (no operators, no bpy.context), because during a render it runs beside the UI;
- it leaves objects in Edit Mode alone: replacing the geometry under an open BMesh loses the edit or worse;
- it skips the rebuild when the file and parameters are those already shown, which makes motion-blur subframes and
  repeated depsgraph updates free.
"""
import atexit
import contextlib
import os
import time
import traceback

import bpy

from .. import api, cache, playback, sequence
from . import arguments as pipeline, fluid_domain, mesh_update, render_policy, render_state, sources
from .surfaces import STATUS_LINE_SEPARATOR, is_surface, surface_objects  # noqa: F401  (re-exported for callers)


class _Memory:
    """What the updater remembers between frames (one instance, module-level: handlers have nowhere else to keep
    it); forgotten on file load and on Reload."""

    def __init__(self):
        # Folder listings and parsed patterns, shared by all surfaces (particle files and caches alike).
        self.sequences = sequence.SequenceCache()
        # What each mesh shows: mesh pointer -> (rebuild key, vertex count). The vertex count guards against a
        # pointer reused by a new mesh and against geometry changed behind our back.
        self.shown = {}
        # Last error message per mesh pointer: the traceback is printed once, not on every frame.
        self.last_error = {}
        # Mesh pointer -> (rebuild key, whether a render has handled it) of a frame that could not be built: a
        # render must apply its policy even when the viewport already failed at the same key.
        self.failed = {}
        # Reconstructed frames per mesh pointer (viewport playback; see playback), all within one memory budget,
        # and the last scene frame each showed, which tells the direction to prefetch in.
        self.budget = playback.MemoryBudget(PLAYBACK_MEMORY_BYTES)
        self.frames = {}
        # Mesh pointer -> name of the surface object that shows it: which kept frames still have a surface.
        self.owners = {}
        self.last_frame = {}
        # Render frames found built ahead by the worker (tests and diagnostics read it).
        self.frames_built_ahead = 0

    def frame_cache(self, pointer):
        frames = self.frames.get(pointer)
        if frames is None:
            frames = self.frames[pointer] = playback.FrameCache(PLAYBACK_MEMORY_BYTES, shared=self.budget)
        return frames

    def release(self, pointer):
        """Drops what is kept for a mesh: its frames, the work queued for it and the record of what it shows."""
        frames = self.frames.pop(pointer, None)
        if frames is not None:
            _prefetcher.forget(frames)
            frames.clear()
        for record in (self.shown, self.last_error, self.failed, self.last_frame, self.owners):
            record.pop(pointer, None)

    def forget(self):
        self.sequences.clear()
        self.shown.clear()
        self.last_error.clear()
        self.failed.clear()
        for frames in self.frames.values():
            _prefetcher.forget(frames)
            frames.clear()
        self.frames.clear()
        self.last_frame.clear()
        self.owners.clear()


# Playback: reconstructed frames kept per surface, up to this many bytes for all surfaces together (scrubbing back is
# instant), and the next PREFETCH_AHEAD frames in the direction of play built by one background thread (only bpy-free
# work runs there).
PLAYBACK_MEMORY_BYTES = 1 << 30
PREFETCH_AHEAD = 3
# A frame change (viewport or render) whose frame the worker is building waits for it to finish: the build started
# earlier and cannot be interrupted, so building the frame a second time beside it could only finish later (at 1 M
# particles a 5 s limit made both builds share the cores: 21 s a frame instead of 11 s).
WORKER_WAIT_SECONDS = 3600.0
_prefetcher = playback.Prefetcher()
# Blender quits without unregistering add-ons: a worker still inside the core when Python finalizes would be torn
# down mid-call (std::terminate). Stopping it at exit waits for the frame under way.
atexit.register(_prefetcher.stop)
_memory = _Memory()


class SurfaceError(Exception):
    """A problem the user can fix (bad pattern, missing file, a parameter out of range): no traceback."""


def forget_cached_state():
    """Drops listings, kept frames and the record of what meshes show, so the next update re-reads everything."""
    _memory.forget()


def forget_handled_failures():
    """A new render applies its own failure policy to frames that failed before (in the viewport, an export or an
    earlier render): they are marked as not handled, so the render rebuilds them instead of keeping what they show."""
    for pointer, (key, _handled) in list(_memory.failed.items()):
        _memory.failed[pointer] = (key, False)


def forget_frames(obj):
    """Drops the frames kept for a surface and the work queued for it (its parameters changed)."""
    try:
        frames = _memory.frames.pop(obj.data.as_pointer(), None)
    except Exception:  # no mesh (being removed)
        return
    if frames is not None:
        _prefetcher.forget(frames)
        frames.clear()


def release_removed_surfaces():
    """Drops the frames kept for meshes that no surface in any scene shows any more (the surface was deleted, unlinked
    or switched off): nothing else would free them until a file is loaded. Returns how many meshes were released."""
    def shows(obj, pointer):
        return is_surface(obj) and obj.data.as_pointer() == pointer and len(obj.users_scene) > 0

    gone = []
    for pointer in set(_memory.frames) | set(_memory.shown):  # one per surface: no walk over every object
        try:
            kept = shows(bpy.data.objects.get(_memory.owners.get(pointer, "")), pointer)
            if not kept:  # renamed, or gone: only then are the objects walked, for one showing the same mesh
                renamed = next((obj for obj in bpy.data.objects if shows(obj, pointer)), None)
                kept = renamed is not None
                if kept:
                    _memory.owners[pointer] = renamed.name
        except Exception:  # data being freed (a file loading): the load handler forgets everything anyway
            kept = False
        if not kept:
            gone.append(pointer)
    for pointer in gone:
        _memory.release(pointer)
    return len(gone)


def held_bytes():
    """Bytes of the frames kept for playback, all surfaces together (the playback cache's own accounting)."""
    return _memory.budget.bytes


def stop_background_work():
    _prefetcher.stop()

def _resolve(path_property, obj, what):
    if not path_property:
        raise SurfaceError(f"No {what} set")
    # Relative paths ('//') are kept in the property and resolved against the .blend (or its library) only here.
    absolute = bpy.path.abspath(path_property, library=obj.library)
    try:
        return _memory.sequences.pattern(os.path.normpath(absolute))
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
    return _memory.sequences.frames(resolve_pattern(obj))


def available_cache_frames(obj):
    return _memory.sequences.frames(resolve_cache_pattern(obj))


def has_cache_frames(obj):
    """Whether a surface's cache folder holds any baked frame."""
    try:
        return bool(available_cache_frames(obj))
    except (SurfaceError, OSError, ValueError):  # no cache folder (yet) or an unusable pattern
        return False


def reconstruction_arguments(settings, for_render, normals=None):
    """api.reconstruct's keyword arguments from a surface's settings; raises SurfaceError naming the panel's
    labels when a value is not allowed (the core would refuse it under its internal name)."""
    arguments = pipeline.pipeline_arguments(settings, for_render, normals)
    problems = pipeline.argument_problems(arguments, for_render)
    if problems:
        raise SurfaceError("; ".join(problems))
    return arguments


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


def _write(mesh, settings, surface, prepared=None):
    """Writes a reconstructed or loaded surface into the Blender mesh (prepared: its mesh_update.SurfaceWrite when the
    worker built it); returns the seconds it took and a status note on attributes stored under another name or not
    at all (the user must find what they asked for)."""
    started = time.perf_counter()
    normals = surface.normals if settings.use_custom_normals else None
    elsewhere = mesh_update.write_surface(mesh, surface.vertices, surface.triangles, normals, surface.attributes,
                                          surface.quads, prepared)
    notes = [f"'{name}' stored as '{stored}'" if stored else f"'{name}' not stored (no Blender type for its shape)"
             for name, stored in sorted(elsewhere.items())]
    return time.perf_counter() - started, "; ".join(notes)


def _face_counts(mesh):
    quads = 0 if mesh.quads is None else len(mesh.quads)
    return f"{len(mesh.triangles):,} triangles" + (f", {quads:,} quads" if quads else "")


def _status_lines(*lines):
    # One fact per line: the panel shows each on its own row, where a narrow sidebar would cut a single long line.
    return STATUS_LINE_SEPARATOR.join(line for line in lines if line)


def _missing_note(result):
    return f"not in the particles: {', '.join(result.missing_attributes)}" if result.missing_attributes else ""


# Sources: each returns (rebuild key, work, what it reads) where work() fills the mesh and returns the status text --

def _file_source(obj, settings, mesh, scene_time, for_render):
    pattern = resolve_pattern(obj)
    lookup = _lookup(_memory.sequences.frames(pattern), pattern, scene_time, settings)
    arguments = reconstruction_arguments(settings, for_render)
    wanted = cache.parse_attribute_names(settings.attribute_names)
    key = _file_key(lookup, arguments, wanted, settings)

    def work():
        if lookup.path is None:
            return _empty_for(mesh, lookup, scene_time, "file")
        if for_render:  # at the render cube size: built ahead while the previous frame rendered, or now
            return _render_file(mesh, settings, lookup.path, key, arguments, wanted)
        return _play_file(obj, settings, mesh, scene_time, pattern, lookup, key, arguments, wanted)

    return key, work, lookup.expected_path


def _file_key(lookup, arguments, wanted, settings):
    # Everything the mesh depends on: the file (and its version on disk) and every reconstruction parameter.
    return ("FILES", lookup.file_frame, lookup.path, _file_version(lookup.path), tuple(sorted(arguments.items())),
            tuple(wanted), settings.use_custom_normals)


def _play_file(obj, settings, mesh, scene_time, pattern, lookup, key, arguments, wanted):
    """The viewport's frame: kept in memory, being built by the worker, or built now; then the next frames are
    queued for the worker."""
    pointer = mesh.as_pointer()
    frames = _memory.frame_cache(pointer)
    result = frames.get(key)
    ready = result is not None
    if result is None:
        result = _prefetcher.wait_for(frames, key, WORKER_WAIT_SECONDS)
    if result is None:  # kept with its prepared write: showing it again later only copies buffers
        result = _with_surface_write(cache.reconstruct_file(lookup.path, arguments, wanted),
                                     settings.use_custom_normals)
        frames.put(key, result)
    status = _show_reconstruction(mesh, settings, os.path.basename(lookup.path), result,
                                  "ready in memory" if ready else "")
    frame = sequence.nearest_frame(scene_time)
    direction = -1 if frame < _memory.last_frame.get(pointer, frame) else 1
    _memory.last_frame[pointer] = frame
    _prefetch(frames, settings, pattern, frame, direction, arguments, wanted)
    return status


def _prefetch(frames, settings, pattern, frame, direction, arguments, wanted):
    listing = _memory.sequences.frames(pattern)
    jobs = []
    for step in range(1, PREFETCH_AHEAD + 1):
        try:
            lookup = _lookup(listing, pattern, frame + direction * step, settings)
        except SurfaceError:
            break
        if lookup.path is not None:
            jobs.append(_worker_job(lookup, arguments, wanted, settings))
    _prefetcher.want(frames, jobs)


def _worker_job(lookup, arguments, wanted, settings):
    """(key, build) of a file frame for the worker. Bound now: the worker reads only these plain values, never the
    settings or anything else of bpy."""
    arguments = dict(arguments)
    custom_normals = settings.use_custom_normals
    return (_file_key(lookup, arguments, wanted, settings),
            lambda path=lookup.path: _with_surface_write(cache.reconstruct_file(path, arguments, wanted),
                                                         custom_normals))


def _with_surface_write(result, custom_normals):
    """The result with its mesh in Blender's layout made beforehand (mesh_update.SurfaceWrite: corners, faces and
    edges from the core, no bpy: the worker runs this), so that Blender's thread only copies buffers when it shows
    the frame; the seconds it took are the hand-off's."""
    started = time.perf_counter()
    surface = result.mesh
    result.surface_write = mesh_update.SurfaceWrite(surface.vertices, surface.triangles,
                                                    surface.normals if custom_normals else None, surface.quads)
    result.handoff_seconds = time.perf_counter() - started
    return result


def _render_file(mesh, settings, path, key, arguments, wanted):
    """A render's frame: taken from the worker when it built it ahead (waiting while it is still at it), else built
    now. A frame the worker could not build is built here again, so its failure reaches the render policy."""
    frames = _memory.frame_cache(mesh.as_pointer())
    if key not in frames:
        _prefetcher.wait_for(frames, key, WORKER_WAIT_SECONDS)
    result = frames.take(key)  # a render shows each frame once: not kept
    if result is None:
        return _build_file(mesh, settings, path, arguments, wanted, True)
    _memory.frames_built_ahead += 1
    return _show_reconstruction(mesh, settings, os.path.basename(path) + " (render, built ahead)", result)


def drop_render_build_ahead():
    """The render ended or was cancelled: build-ahead work not yet started is dropped (only build-ahead queues work
    during a render). Touches nothing of bpy, since render_complete / render_cancel may run on the render thread."""
    for frame_cache in list(_memory.frames.values()):
        _prefetcher.forget(frame_cache)


def build_next_render_frame(scene):
    """During an animation render: queues the next frame of every surface built from particle files on the worker,
    which builds it while Blender renders this one. Never raises (a problem of that frame is reported when its own
    frame change builds it)."""
    next_frame = scene.frame_current + max(scene.frame_step, 1)
    if next_frame > scene.frame_end:
        return
    for obj in surface_objects(scene):
        try:
            settings = obj.meniscus
            if settings.use_native_cache or settings.use_cache or settings.source_type != "FILES":
                continue  # baked meshes load fast; a live source exists only at the frame being evaluated
            pattern = resolve_pattern(obj)
            lookup = _lookup(_memory.sequences.frames(pattern), pattern, next_frame, settings)
            if lookup.path is None:
                continue
            arguments = reconstruction_arguments(settings, for_render=True)
            wanted = cache.parse_attribute_names(settings.attribute_names)
            _prefetcher.want(_memory.frame_cache(obj.data.as_pointer()), [_worker_job(lookup, arguments, wanted, settings)])
        except Exception:  # not this frame's problem: the next frame change builds it itself and reports
            continue


def _build_file(mesh, settings, path, arguments, wanted, for_render):
    result = cache.reconstruct_file(path, arguments, wanted)
    return _show_reconstruction(mesh, settings, os.path.basename(path) + (" (render)" if for_render else ""), result)


def _cache_source(obj, settings, mesh, scene_time, for_render, scene=None, depsgraph=None):
    pattern = resolve_cache_pattern(obj)
    lookup = _lookup(_memory.sequences.frames(pattern), pattern, scene_time, settings)
    key = ("CACHE", lookup.file_frame, lookup.path, _file_version(lookup.path), settings.use_custom_normals)
    if scene is not None and settings.source_type == "OBJECT" and fluid_domain.is_liquid_domain(settings.source_object):
        if lookup.path:
            return _domain_cache_source(obj, settings, mesh, scene, depsgraph, scene_time, for_render, lookup, key)
        if lookup.file_frame is not None and fluid_domain.has_frame(settings.source_object,
                                                                    lookup.file_frame - settings.frame_offset):
            # Outside a partial bake: the domain's cache still has the frame, so it is rebuilt from there.
            return _object_source(obj, settings, mesh, scene, depsgraph, scene_time, for_render)

    has_particles = settings.file_pattern and settings.source_type == "FILES"
    if lookup.path is None and lookup.file_frame is not None and has_particles:
        # Outside a partial bake: the particle files are still there, so the frame is rebuilt from them.
        return _file_source(obj, settings, mesh, scene_time, for_render)
    stale = _stale_cache_frame(obj, settings, lookup.path, lookup.file_frame) if lookup.path and has_particles else ""
    if stale:
        name = os.path.basename(lookup.path)
        particles = _particle_file(obj, lookup.file_frame)
        if particles is None:  # nothing to rebuild it from: refused, never shown as if current
            raise SurfaceError(f"Stale baked frame {name}: {stale}; bake again")
        key, work, source = _file_source(obj, settings, mesh, scene_time, for_render)
        return key, lambda: _status_lines(f"Stale baked frame {name} ({stale}): rebuilt from the particles", work()), source

    def work():
        if lookup.path is None:
            return _empty_for(mesh, lookup, scene_time, "baked frame")
        return _load_cached_file(mesh, settings, lookup.path)

    return key, work, lookup.expected_path


def _domain_cache_source(obj, settings, mesh, scene, depsgraph, scene_time, for_render, lookup, key):
    """A baked frame of a fluid domain's surface: played when its record says it was made from this frame's cache
    file with the surface's parameters and the domain as it is now (settings, place, obstacles), else rebuilt from
    the domain's cache, or refused when that cache is gone."""
    name = os.path.basename(lookup.path)
    scene_time = lookup.file_frame - settings.frame_offset  # the frame baked into this file (file = scene + offset)
    stale, particles, record = _stale_domain_frame(settings, scene, depsgraph, lookup.path, scene_time)
    if not stale:
        # The record is part of the key: a changed domain makes the same file stale without a frame change.
        return key + (record,), (lambda: _load_cached_file(mesh, settings, lookup.path)), lookup.expected_path
    if particles is None:
        raise SurfaceError(f"Stale baked frame {name}: {stale}; bake again")
    key, work, source = _object_source(obj, settings, mesh, scene, depsgraph, scene_time, for_render)
    note = f"Stale baked frame {name} ({stale}): rebuilt from the fluid cache"
    return key, lambda: _status_lines(note, work()), source


def _stale_domain_frame(settings, scene, depsgraph, path, scene_time):
    """(why the baked frame at path was not made from the domain's cache file of scene_time with the surface's
    parameters and the domain as it is now, '' when it was; that particle file or None when it is gone; the record
    it was checked against)."""
    domain = settings.source_object
    try:
        arguments = reconstruction_arguments(settings, for_render=True, normals=True)
        given = fluid_domain.domain_arguments(domain, scene, scene_time, depsgraph)
        try:
            particles = fluid_domain.particle_file(domain, scene_time)
        except fluid_domain.DomainError:  # Blender deleted the domain's cache (a setting changed): the record alone
            particles = None
        wanted = cache.parse_attribute_names(settings.attribute_names)
        record = cache.provenance(particles, {**arguments, "fluid_domain": given}, wanted)
        return pipeline.in_panel_terms(cache.stale_reason(path, record), for_render=True), particles, record
    except (SurfaceError, ValueError) as error:  # no bake could be current: rebuilding shows the refusal
        return f"the settings are refused: {error}", None, None


def _particle_file(obj, file_frame):
    try:
        return _memory.sequences.frames(resolve_pattern(obj)).get(file_frame)
    except (SurfaceError, OSError, ValueError):
        return None


def _stale_cache_frame(obj, settings, path, file_frame):
    """Why a baked frame was not made from this frame's particle file with the surface's current parameters (as a
    bake would make it now: render settings, normals); '' when it was. Without the particle file, the parameters
    alone are checked."""
    try:
        arguments = reconstruction_arguments(settings, for_render=True, normals=True)
    except SurfaceError as error:  # no bake could be current: rebuilding shows the refusal
        return f"the settings are refused: {error}"
    wanted = cache.parse_attribute_names(settings.attribute_names)
    reason = cache.stale_reason(path, cache.provenance(_particle_file(obj, file_frame), arguments, wanted))
    return pipeline.in_panel_terms(reason, for_render=True)  # a bake's cube size is the render one


def _load_cached_file(mesh, settings, path):
    started = time.perf_counter()
    surface = cache.load_mesh(path)
    loaded = time.perf_counter() - started
    blender_seconds, attribute_note = _write(mesh, settings, surface)
    return _status_lines(f"{os.path.basename(path)} (cache)", _face_counts(surface),
                         f"{loaded:.2f} s loading + {blender_seconds:.2f} s in Blender", attribute_note)


def _object_source(obj, settings, mesh, scene, depsgraph, scene_time, for_render):
    source = settings.source_object
    if source is None:
        raise SurfaceError("No source object set")
    if source == obj:
        raise SurfaceError("A surface cannot be its own source")
    wanted = cache.parse_attribute_names(settings.attribute_names)
    domain, domain_digest = None, None
    if fluid_domain.is_liquid_domain(source):
        frame = fluid_domain.read_frame(source, scene, scene_time, api, depsgraph,
                                        fluid_domain.core_fills_narrow_band(api))
        positions, attributes, kind, domain, domain_digest = (frame.positions, frame.attributes, frame.kind,
                                                              frame.domain, frame.digest)
    else:
        positions, attributes, kind = sources.object_particles(source, depsgraph, wanted)
    if len(positions) == 0:
        raise SurfaceError(f"'{source.name}' has no particles at frame {int(round(scene_time))} ({kind})")
    arguments = reconstruction_arguments(settings, for_render)
    # The positions themselves are the key: the source may change without a frame change (an edit, a re-bake); and
    # for a domain what the fill uses besides them (its settings, obstacles, the cache file), which may change too.
    key = ("OBJECT", source.name, sources.digest(positions), domain_digest, tuple(sorted(arguments.items())),
           tuple(wanted), settings.use_custom_normals)

    def work():
        with_domain = arguments if domain is None else {**arguments, "fluid_domain": domain}
        result = cache.reconstruct_positions(positions, attributes, with_domain, wanted)
        return _show_reconstruction(mesh, settings, f"{source.name}: {kind}" + (" (render)" if for_render else ""), result)

    return key, work, f"object '{source.name}'"


def _show_reconstruction(mesh, settings, label, result, note=""):
    """Writes a reconstruction (from files or from an object) into the mesh; returns the status lines, which time
    the whole frame change: the core (reading included), the hand-off (the mesh put in Blender's layout) and Blender
    (the buffers copied into the mesh), or only Blender's part for a frame that was ready in memory."""
    if getattr(result, "surface_write", None) is None:
        _with_surface_write(result, settings.use_custom_normals)
    blender_seconds, attribute_note = _write(mesh, settings, result.mesh, result.surface_write)
    timing = f"{blender_seconds:.2f} s in Blender, {note}" if note else \
        f"{result.seconds:.2f} s core + {result.handoff_seconds:.2f} s hand-off + {blender_seconds:.2f} s in Blender"
    return _status_lines(label, f"{result.particle_count:,} particles", _face_counts(result.mesh), timing,
                         _missing_note(result), attribute_note)


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


_suspended = 0


class ExportRecord:
    """What an export of a surface's frames (native_cache) met: the frames it built from particle files at the
    render cube size, those loaded from the bake, and those that could not be built (scene frame -> (message, the
    file held instead or None))."""

    def __init__(self, obj):
        self.pointer = obj.data.as_pointer()
        self.built = set()
        self.from_cache = set()
        self.failed = {}


_export = None


@contextlib.contextmanager
def exporting(obj):
    """Inside, the surface obj is built as a final render builds it (the render cube size), and a frame that cannot
    be built follows "If a Frame Fails" without stopping Blender: it is recorded in the ExportRecord yielded, for the
    export to fail (Stop) or list it (Hold, Empty). Other surfaces are left as they are meanwhile (not exported)."""
    global _export
    record = _export = ExportRecord(obj)
    try:
        yield record
    finally:
        _export = None


@contextlib.contextmanager
def updates_suspended():
    """No surface is rebuilt inside: a bake steps the scene through its frames only to read the container's bounds."""
    global _suspended
    _suspended += 1
    try:
        yield
    finally:
        _suspended -= 1


def update_surface(obj, scene, force=False, depsgraph=None):
    """Makes a surface object show the scene's current frame. Never raises.

    Returns True when the mesh was rebuilt (or emptied), False when nothing had to be done or it was skipped.
    """
    if _suspended:
        return False
    try:
        settings = obj.meniscus
        if settings.use_native_cache:  # the Mesh Sequence Cache modifier plays the exported file (native_cache)
            return False
        mesh = obj.data
        if obj.mode == "EDIT" or mesh.is_editmode:
            return False
        pointer = mesh.as_pointer()
        name, frame = obj.name, scene.frame_current
        _memory.owners[pointer] = name
        # Fractional during motion-blur shutter steps; the sequence module rounds it to the nearest file frame.
        scene_time = frame + scene.frame_subframe
        is_subframe = scene.frame_subframe != 0.0
    except Exception:  # the object or its mesh was removed while we held a reference
        return False

    key = None
    source = None
    exported = _export is not None and _export.pointer == pointer
    if _export is not None and not exported:
        return False
    for_render = render_state.is_rendering() or exported
    try:
        if settings.use_cache:
            key, work, source = _cache_source(obj, settings, mesh, scene_time, for_render, scene, depsgraph)
        elif settings.source_type == "OBJECT":
            if is_subframe and pointer in _memory.shown and not force:
                # A live simulation moves at every shutter step; one surface per frame is enough (the velocity
                # attribute carries the motion), so subframes keep what the frame built.
                return False
            key, work, source = _object_source(obj, settings, mesh, scene, depsgraph, scene_time, for_render)
        else:
            key, work, source = _file_source(obj, settings, mesh, scene_time, for_render)

        # A frame the viewport failed to build at the same key is not done yet for a render: its policy applies.
        unhandled_failure = for_render and _memory.failed.get(pointer) == (key, False)
        if not force and not unhandled_failure and _memory.shown.get(pointer) == (key, len(mesh.vertices)):
            return False
        # Recorded before the work so that a failing file is not retried on every subframe of the same frame.
        _memory.shown[pointer] = (key, -1)
        try:
            _set_status(settings, work())
            if exported:
                (_export.from_cache if key[0] == "CACHE" else _export.built).add(frame)
        except _Blank as blank:
            _set_status(settings, str(blank))
        _memory.shown[pointer] = (key, len(mesh.vertices))
        _memory.last_error.pop(pointer, None)
        _memory.failed.pop(pointer, None)
        return True
    except Exception as error:
        message = str(error) or type(error).__name__
        # Unreadable files are the user's to fix and the message names file and fault: no traceback for those.
        # MemoryError carries the core's estimate of the grid it refused to allocate: a parameter to change too.
        # ValueError: the core refusing the particles or a value (NaN coordinates, a grid too large).
        expected = isinstance(error, (SurfaceError, api.FormatError, OSError, MemoryError, ValueError))
        if isinstance(error, MemoryError) and not str(error):
            message = "Out of memory: use a larger cube size"
        message = pipeline.in_panel_terms(message, for_render)
        if _memory.last_error.get(pointer) != message:  # once per distinct problem, not on every frame
            print(f"Meniscus: '{name}' at frame {frame}: {message}")
            if not expected:
                traceback.print_exc()
        _memory.last_error[pointer] = message
        status = message if expected else f"Error: {message}"
        if exported:
            status = _apply_export_policy(obj, settings, mesh, scene, scene_time, frame, message)
        elif for_render:
            status = _apply_render_policy(obj, settings, mesh, scene, scene_time, frame, render_policy.failure_message(
                name, frame, source, message))
        else:
            mesh_update.clear_surface(mesh)
        try:
            if key is None:  # failed before knowing what to show: nothing to remember, try again next time
                _memory.shown.pop(pointer, None)
            else:
                _memory.shown[pointer] = (key, len(mesh.vertices))
                # An export under Stop fails afterwards rather than applying the render's policy: not handled for
                # a render, so a later F12 at this frame applies its own.
                _memory.failed[pointer] = (key, for_render and not exported)
            _set_status(settings, status, is_error=True)
        except Exception:
            traceback.print_exc()
        return True


def _apply_render_policy(obj, settings, mesh, scene, scene_time, frame, message):
    """In a final render, what a frame that cannot be built shows (see render_policy); returns the status text.
    STOP does not return in a render without a UI."""
    policy = settings.render_failure
    if policy == render_policy.HOLD:
        held = _hold_earlier_frame(obj, settings, mesh, scene, scene_time)
        if held is not None:
            print(f"{message}\nMeniscus: holding {held[0]} instead")
            return _status_lines(f"Holding {held[0]} (this frame failed)", held[1])
        message += f"; no earlier frame could be built to hold (tried {render_policy.HOLD_TRIES})"
    mesh_update.clear_surface(mesh)
    if policy == render_policy.EMPTY:
        print(f"{message}\nMeniscus: rendering the frame without this surface")
    else:
        render_policy.stop_render(message, frame)
    return message


def _apply_export_policy(obj, settings, mesh, scene, scene_time, frame, message):
    """In an export, what a frame that cannot be built shows: the render policy's frame, without stopping Blender
    (the export itself fails afterwards under Stop, naming every such frame); returns the status text."""
    holding = settings.render_failure == render_policy.HOLD
    held = _hold_earlier_frame(obj, settings, mesh, scene, scene_time) if holding else None
    if held is not None:
        _export.failed[frame] = (message, held[0])
        return _status_lines(f"Holding {held[0]} (this frame failed)", held[1])
    if holding:
        message += f"; no earlier frame could be built to hold (tried {render_policy.HOLD_TRIES})"
    _export.failed[frame] = (message, None)
    mesh_update.clear_surface(mesh)
    return message


def _hold_earlier_frame(obj, settings, mesh, scene, scene_time):
    """Builds the nearest earlier file frame that builds; returns (its file name, status) or None."""
    if settings.source_type == "OBJECT" and not settings.use_cache:
        return _hold_earlier_domain_frame(obj, settings, mesh, scene, scene_time)
    try:
        pattern = resolve_cache_pattern(obj) if settings.use_cache else resolve_pattern(obj)
        frames = _memory.sequences.frames(pattern)
        failed_frame = sequence.resolve_file_frame(scene_time, settings.frame_offset, settings.frame_start,
                                                   settings.frame_end, settings.out_of_range)
        if not settings.use_cache:
            arguments = reconstruction_arguments(settings, for_render=True)
            wanted = cache.parse_attribute_names(settings.attribute_names)
    except Exception:  # the sequence itself is unusable: nothing to hold
        return None
    for file_frame in render_policy.earlier_frames(frames, failed_frame):
        path = frames[file_frame]
        try:
            if settings.use_cache:
                stale = _stale_cache_frame(obj, settings, path, file_frame) if settings.file_pattern and \
                    settings.source_type == "FILES" else ""
                if settings.source_type == "OBJECT" and fluid_domain.is_liquid_domain(settings.source_object):
                    stale = _stale_domain_frame(settings, scene, None, path, file_frame - settings.frame_offset)[0]
                if stale:  # a frame of other parameters is no better to hold than none
                    raise SurfaceError(f"stale baked frame ({stale})")
                return os.path.basename(path), _load_cached_file(mesh, settings, path)
            return os.path.basename(path), _build_file(mesh, settings, path, arguments, wanted, True)
        except Exception as error:
            print(f"Meniscus: cannot hold {path} either: {error}")
    return None


def _hold_earlier_domain_frame(obj, settings, mesh, scene, scene_time):
    """A fluid domain's nearest earlier baked frame that builds; a live object has no earlier frames (None)."""
    source = settings.source_object
    if not fluid_domain.is_liquid_domain(source):
        return None
    try:
        baked = fluid_domain.baked_scene_frames(source)
    except Exception:  # the cache folder is unusable: nothing to hold
        return None
    for scene_frame in render_policy.earlier_frames(baked, int(round(scene_time))):
        try:
            _, work, _ = _object_source(obj, settings, mesh, scene, None, scene_frame, for_render=True)
            return os.path.basename(fluid_domain.particle_file(source, scene_frame)), work()
        except Exception as error:
            print(f"Meniscus: cannot hold frame {scene_frame} of '{source.name}' either: {error}")
    return None


def update_scene(scene, force=False, depsgraph=None):
    """Updates every surface object of a scene; returns how many meshes were rebuilt."""
    rebuilt = 0
    for obj in surface_objects(scene):
        rebuilt += bool(update_surface(obj, scene, force, depsgraph))
    return rebuilt
