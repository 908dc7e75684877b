"""Baking surfaces to a mesh cache, and playing caches (also ones written by the `meniscus` command line).

In the UI the bake runs in a background thread that only reads particle files and writes mesh files (it never
touches Blender data); a modal operator polls it from a timer, drives the progress bar and handles Esc. From a
script or the command line the same bake runs synchronously:

    blender -b scene.blend --python-expr "import bpy; bpy.ops.meniscus.bake(object_name='Fluid')"
    # or, with more control:  from meniscus.blender import bake; bake.bake_surface(bpy.data.objects['Fluid'])

Either way the surface switches to "Play From Cache" afterwards, and the .blend (if saved) renders from the cache.
"""
import dataclasses
import functools
import os

import bpy
from bpy.props import BoolProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from .. import cache, sequence
from . import arguments as pipeline, container, fluid_domain, operators, surfaces, update

# Running UI bakes by object name (names, not references: undo and file loads invalidate object references).
_jobs = {}


class BakeError(Exception):
    pass


def job_for(obj):
    """The bake running for a surface object, if any (for the panel's progress bar)."""
    return _jobs.get(obj.name) if obj is not None else None


def _cache_pattern_for_bake(obj):
    """The cache pattern the bake writes: the surface's (or the default), with the chosen format's extension."""
    settings = obj.meniscus
    stored = update.cache_pattern_string(obj)
    if stored.startswith("//") and not bpy.data.is_saved:
        raise BakeError("Save the .blend first, or choose Cache Files: the cache goes next to the .blend")
    root, extension = os.path.splitext(stored)
    wanted = cache.FORMAT_EXTENSIONS[settings.cache_format]
    if extension.lower() != wanted:
        stored = root + wanted
    absolute = os.path.normpath(bpy.path.abspath(stored, library=obj.library))
    try:
        return stored, sequence.parse_pattern(absolute, sibling_names=())
    except ValueError as error:
        raise BakeError(f"Cache Files: {error}") from None


def _moves(obj):
    # Animated itself or through a parent, or constrained: its bounds may differ from frame to frame.
    while obj is not None:
        animation = obj.animation_data
        if len(obj.constraints) or (animation is not None and (animation.action is not None or len(animation.drivers))):
            return True
        obj = obj.parent
    return False


def _with_container_boxes(settings, scene, tasks):
    """The tasks with the container's box at each one's frame when the container moves (the bake runs outside
    Blender's frame changes, so the boxes are read now, stepping the scene through the frames, rebuilding nothing)."""
    if settings.container_object is None or scene is None or not _moves(settings.container_object):
        return tasks
    frame, subframe = scene.frame_current, scene.frame_subframe
    boxed = []
    with update.updates_suspended():
        try:
            for task in tasks:
                scene.frame_set(task.frame - settings.frame_offset)  # file frame = scene frame + offset
                boxed.append(dataclasses.replace(task, arguments=container.box_arguments(settings)))
        finally:
            scene.frame_set(frame, subframe=subframe)
    return boxed


def prepare_bake(obj, frame_start=None, frame_end=None, scene=None):
    """Reads everything the bake needs from Blender data (main thread only); returns (job, stored pattern)."""
    if not surfaces.is_surface(obj):
        raise BakeError(f"'{getattr(obj, 'name', obj)}' is not a Meniscus surface")
    settings = obj.meniscus
    if settings.source_type == "OBJECT" and fluid_domain.is_liquid_domain(settings.source_object):
        return _prepare_domain_bake(obj, frame_start, frame_end, scene or bpy.context.scene)
    if settings.source_type != "FILES":
        raise BakeError("Baking needs a particle file sequence or a fluid domain as the source")
    try:
        frames = update.available_frames(obj)
    except update.SurfaceError as error:
        raise BakeError(str(error)) from None
    first = settings.frame_start if frame_start is None else frame_start
    last = settings.frame_end if frame_end is None else frame_end
    stored, pattern = _cache_pattern_for_bake(obj)
    # The files' frames within the range, not the range's numbers: a range typed as 0-2147483647 costs nothing.
    tasks = [cache.BakeTask(frame, frames[frame], pattern.path(frame)) for frame in sorted(frames)
             if first <= frame <= last]
    if not tasks:
        raise BakeError(f"No particle files in frames {first}-{last}")
    problem = cache.writable_folder_problem(pattern.directory)  # before any frame is reconstructed
    if problem:
        raise BakeError(f"Cache Files: cannot write to '{pattern.directory}' ({problem})")
    cache.remove_abandoned_partials(pattern.directory)  # left by a bake that was killed
    # Bakes are for final output: render resolution, and normals always (playback may switch custom normals on).
    try:
        arguments = update.reconstruction_arguments(settings, for_render=True, normals=True)
    except update.SurfaceError as error:
        raise BakeError(str(error)) from None
    tasks = _with_container_boxes(settings, scene or bpy.context.scene, tasks)
    wanted = cache.parse_attribute_names(settings.attribute_names)
    return cache.BakeJob(tasks, arguments, wanted), stored


def _prepare_domain_bake(obj, frame_start, frame_end, scene):
    """prepare_bake for a fluid domain source: its baked frames, each cache file numbered like a file source's (file
    frame = scene frame + Frame Offset). What the fill needs that only Blender knows (the domain's matrix and settings,
    its obstacles at the cache frame, a moving container's box) is evaluated here, stepping the scene through the
    frames on the main thread; the bake's thread then only reads the cache files and reconstructs."""
    settings = obj.meniscus
    domain = settings.source_object
    frames = [frame + settings.frame_offset for frame in fluid_domain.baked_scene_frames(domain)]
    if not frames:
        raise BakeError(f"'{domain.name}' has no baked frames in its cache folder {fluid_domain.cache_folder(domain)}")
    first = min(frames) if frame_start is None else frame_start
    last = max(frames) if frame_end is None else frame_end
    frames = [frame for frame in frames if first <= frame <= last]
    if not frames:
        raise BakeError(f"No baked frames of '{domain.name}' in frames {first}-{last}")
    stored, pattern = _cache_pattern_for_bake(obj)
    problem = cache.writable_folder_problem(pattern.directory)  # before any frame is reconstructed
    if problem:
        raise BakeError(f"Cache Files: cannot write to '{pattern.directory}' ({problem})")
    cache.remove_abandoned_partials(pattern.directory)
    try:
        arguments = update.reconstruction_arguments(settings, for_render=True, normals=True)
    except update.SurfaceError as error:
        raise BakeError(str(error)) from None
    prepare = functools.partial(fluid_domain.placed, with_fill=fluid_domain.core_fills_narrow_band(update.api))
    moving_container = settings.container_object is not None and _moves(settings.container_object)
    tasks = []
    frame, subframe = scene.frame_current, scene.frame_subframe
    with update.updates_suspended():
        try:
            for file_frame in frames:
                scene_frame = file_frame - settings.frame_offset
                scene.frame_set(scene_frame)
                depsgraph = bpy.context.evaluated_depsgraph_get()
                given = {"fluid_domain": fluid_domain.domain_arguments(domain, scene, scene_frame, depsgraph)}
                if moving_container:
                    given.update(container.box_arguments(settings))
                tasks.append(cache.BakeTask(file_frame, fluid_domain.particle_file(domain, scene_frame),
                                            pattern.path(file_frame), given, prepare))
        except fluid_domain.DomainError as error:
            raise BakeError(str(error)) from None
        finally:
            scene.frame_set(frame, subframe=subframe)
        if settings.frame_start == settings.frame_end == 0:  # never set (a file source's range): the baked frames play
            settings.frame_start, settings.frame_end = first, last
    wanted = cache.parse_attribute_names(settings.attribute_names)
    return cache.BakeJob(tasks, arguments, wanted), stored


def finish_bake(obj, job, stored_pattern, scene=None):
    """Switches the surface to its new cache and shows the current frame from it. Returns a summary line."""
    settings = obj.meniscus
    written = job.completed - len(job.failures)
    if written > 0:
        settings.is_surface = False  # several fields change: one rebuild at the end, not one per field
        settings.cache_pattern = stored_pattern
        settings.use_cache = True
        settings.is_surface = True
    update.forget_cached_state()  # the cache folder changed under the listings
    if scene is not None:
        update.update_surface(obj, scene, force=True)
    summary = f"Baked {written} of {job.total} frames in {job.seconds:.1f} s"
    if job.cancelled:
        summary += " (cancelled)" + _stale_note(job)
    return summary + _failure_note(job)


def _stale_note(job):
    """The frames a cancelled bake left from an earlier one with other parameters: named, never played as baked
    (playback rebuilds them from the particle files, or refuses them without those)."""
    stale = job.stale_frames()
    if not stale:
        return ""
    frames = sorted(stale)
    return (f"; {len(frames)} cached frames ({sequence.describe_frames(frames)}) are from an earlier bake, "
            f"{pipeline.in_panel_terms(stale[frames[0]])}: they are rebuilt from the particle files, not played "
            "from the cache")


def _failure_note(job):
    """Why frames failed, in the words of the first failure (the others are usually the same)."""
    if not job.failures:
        return ""
    first_frame = min(job.failures)
    reason = pipeline.in_panel_terms(str(job.failures[first_frame]))
    return f"; {len(job.failures)} failed, first {first_frame}: {reason}"


def bake_surface(obj, scene=None, frame_start=None, frame_end=None, report=print):
    """Bakes synchronously (scripts, command line, render farms); returns the finished cache.BakeJob."""
    job, stored = prepare_bake(obj, frame_start, frame_end, scene)

    def progress(job_, task, result):
        state = job_.failures.get(task.frame, f"{len(result.mesh.triangles):,} triangles" if result else "")
        report(f"Meniscus bake '{obj.name}': frame {task.frame} ({job_.completed}/{job_.total}) {state}")

    job.on_frame = progress
    job.run()
    report(finish_bake(obj, job, stored, scene if scene is not None else bpy.context.scene))
    return job


class MENISCUS_OT_bake(bpy.types.Operator):
    """Reconstruct the frame range into a cache folder; afterwards the surface plays from the cache (scrubbing
    and rendering only load files). Runs in the background with a progress bar; Esc cancels"""
    bl_idname = "meniscus.bake"
    bl_label = "Bake"
    bl_options = {"REGISTER"}  # no UNDO: the files on disk cannot be undone, the settings change would be

    object_name: StringProperty(name="Object", description="Surface to bake (default: the active object)")
    use_surface_range: BoolProperty(
        name="Surface's Range", description="Bake the surface's Start-End range of file frames", default=True)
    frame_start: IntProperty(name="Start", description="First file frame to bake")
    frame_end: IntProperty(name="End", description="Last file frame to bake")

    _timer = None
    _job = None
    _stored = None
    _name = None

    def _target(self, context):
        if self.object_name:
            return bpy.data.objects.get(self.object_name)
        return context.active_object

    def _range(self):
        return (None, None) if self.use_surface_range else (self.frame_start, self.frame_end)

    def execute(self, context):
        obj = self._target(context)
        try:
            job = bake_surface(obj, context.scene, *self._range(), report=print)
        except BakeError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        written = job.completed - len(job.failures)
        # The reason goes into the report too: a script or a headless bake sees only this line.
        self.report({"INFO"} if written else {"ERROR"}, f"Baked {written} of {job.total} frames" + _failure_note(job))
        return {"FINISHED"} if written else {"CANCELLED"}

    def invoke(self, context, _event):
        obj = self._target(context)
        if obj is not None and obj.name in _jobs:
            self.report({"WARNING"}, f"'{obj.name}' is already baking")
            return {"CANCELLED"}
        try:
            self._job, self._stored = prepare_bake(obj, *self._range())
        except BakeError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self._name = obj.name
        _jobs[self._name] = self._job
        self._job.start()
        window_manager = context.window_manager
        self._timer = window_manager.event_timer_add(0.2, window=context.window)
        window_manager.progress_begin(0, self._job.total)
        window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        job = self._job
        if event.type == "ESC" and event.value == "PRESS":
            job.cancel()  # the thread stops after the current frame; we finish once it has
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        context.window_manager.progress_update(job.completed)
        _redraw_sidebars(context)
        if not job.done:
            return {"PASS_THROUGH"}
        return self._finish(context)

    def _finish(self, context):
        window_manager = context.window_manager
        window_manager.event_timer_remove(self._timer)
        window_manager.progress_end()
        _jobs.pop(self._name, None)
        obj = bpy.data.objects.get(self._name)  # looked up again: undo may have replaced the object meanwhile
        if obj is None or not surfaces.is_surface(obj):
            self.report({"WARNING"}, "The baked surface no longer exists; the files are kept")
            return {"CANCELLED"}
        summary = finish_bake(obj, self._job, self._stored, context.scene)
        self.report({"WARNING"} if self._job.failures or self._job.cancelled else {"INFO"}, summary)
        _redraw_sidebars(context)
        return {"FINISHED"}

    def cancel(self, context):
        # Blender ends the modal without our _finish (e.g. the file is closed): stop the thread, drop the timer.
        if self._job is not None:
            self._job.cancel()
        _jobs.pop(self._name, None)
        try:
            context.window_manager.event_timer_remove(self._timer)
            context.window_manager.progress_end()
        except Exception:
            pass


class MENISCUS_OT_bake_cancel(bpy.types.Operator):
    """Stop the running bake after the frame being computed (the frames already baked are kept)"""
    bl_idname = "meniscus.bake_cancel"
    bl_label = "Cancel Bake"

    object_name: StringProperty(name="Object")

    def execute(self, context):
        job = _jobs.get(self.object_name or getattr(context.active_object, "name", ""))
        if job is None:
            return {"CANCELLED"}
        job.cancel()
        return {"FINISHED"}


class MENISCUS_OT_add_cache(bpy.types.Operator, ImportHelper):
    """Add a surface object that plays a folder of mesh files, one per frame (baked here or written by the
    meniscus command line, e.g. surface_0001.ply)"""
    bl_idname = "meniscus.add_cache"
    bl_label = "Add Mesh Cache"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ""
    filter_glob: StringProperty(default="*.npz;*.ply;*.obj;*.vtk", options={"HIDDEN"})
    relative_path: BoolProperty(name="Relative Path", description="Store the path relative to the .blend file",
                                default=True)

    def execute(self, context):
        found = operators.find_sequence(self, self.filepath, "mesh files")
        if found is None:
            return {"CANCELLED"}
        pattern, frames, first, last = found
        stored = operators.stored_path(pattern.pattern_string(), self.relative_path)
        def configure(settings):
            settings.cache_pattern = stored
            settings.use_cache = True
            settings.frame_start, settings.frame_end = first, last

        obj = operators.add_surface_object(context, pattern.prefix.rstrip("_-. ") or "Fluid Cache", configure)
        self.report({"INFO"}, f"Added '{obj.name}': {len(frames)} cached frames ({first}-{last})")
        return {"FINISHED"}


def _redraw_sidebars(context):
    for window in context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


classes = (MENISCUS_OT_bake, MENISCUS_OT_bake_cancel, MENISCUS_OT_add_cache)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for job in list(_jobs.values()):
        job.cancel()
    _jobs.clear()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
