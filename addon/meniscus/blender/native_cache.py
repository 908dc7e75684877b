"""Renders without the add-on: a surface's frames written as an Alembic mesh sequence through Blender's own exporter
and played back by a Mesh Sequence Cache modifier, which every Blender reads without Meniscus (a render farm node
where the add-on is not installed renders the same frames).

Alembic rather than USD: Blender 3.4, 4.x and 5.x all export and read it with changing topology per frame; the
exporter writes the mesh's normals (custom normals included) and its 'velocity' point attribute as the velocities
that the modifier gives back for motion blur.

The export steps the scene through the frames; at each, the surface is built as a final render builds it (from the
mesh cache right after a bake, so it is quick; else at the render cube size) and the exporter records it. A frame
that cannot be built follows "If a Frame Fails": Stop fails the export naming every such frame (the file is not
written), Hold and Empty export it held or empty and the operator's report lists it. Afterwards the surface carries the
modifier and `settings.use_native_cache`: the add-on no longer rebuilds it, so what the viewport and the render show
with and without the add-on is the same file.
"""
import collections
import os
import shutil

import bpy

from .. import busy_files
from . import mesh_update, render_policy, surfaces, update

MODIFIER_NAME = "Meniscus Alembic"


class NativeCacheError(Exception):
    pass


# path: the file written; frames: how many; cube_size: the render cube size of the frames built from particle files
# (None when all came from the bake); from_cache: how many came from the bake; failed: scene frame -> (reason, the
# file held instead or None) of the frames that could not be built (held or empty in the file).
ExportResult = collections.namedtuple("ExportResult", "path frames cube_size from_cache failed")


def _frame_list(frames):
    return ", ".join(str(frame) for frame in sorted(frames))


def summary(result):
    """The operator's report: how many frames went where at which resolution, and the frames that failed."""
    if result.cube_size is None:
        how = "from the baked meshes"
    else:
        how = f"at render cube size {result.cube_size:g}"
        if result.from_cache:
            how = f"{how} ({result.from_cache} from the baked meshes)"
    text = f"Wrote {result.frames} frames {how} to {result.path}"
    held = {frame: file for frame, (_, file) in result.failed.items() if file}
    empty = [frame for frame, (_, file) in result.failed.items() if not file]
    if held:
        text += "; frames that could not be built, held: " + ", ".join(
            f"{frame} ({held[frame]})" for frame in sorted(held))
    if empty:
        text += f"; frames that could not be built, empty: {_frame_list(empty)}"
    return text + "; the surface plays it now (Remove to rebuild again)"


def can_export():
    """Whether this Blender has Alembic (Debian's Blender 3.4 package, for one, is built without it)."""
    return "alembic_export" in dir(bpy.ops.wm) and "alembic_import" in dir(bpy.ops.wm)


def alembic_path(obj):
    """Where the Alembic file goes: beside the surface's mesh cache (or the .blend), named after the object."""
    folder = os.path.dirname(bpy.path.abspath(update.cache_pattern_string(obj), library=obj.library))
    return os.path.join(folder, f"{bpy.path.clean_name(obj.name)}.abc")


def export_alembic(obj, scene, frame_start, frame_end, filepath=None):
    """Writes the surface's scene frames frame_start..frame_end, built at render settings, into an Alembic file and
    makes the surface play it; returns an ExportResult. Raises NativeCacheError when a frame cannot be built and the
    surface's "If a Frame Fails" is Stop (or Hold found nothing to hold), naming the frames; the file is then not
    written (an earlier one stays, and plays on where it played)."""
    if not surfaces.is_surface(obj):
        raise NativeCacheError(f"'{getattr(obj, 'name', obj)}' is not a Meniscus surface")
    if not can_export():
        raise NativeCacheError(f"This Blender ({bpy.app.version_string}) was built without Alembic: export from a "
                               "build that has it (blender.org's builds do)")
    filepath = os.path.abspath(filepath or alembic_path(obj))
    if "//" in filepath or not os.path.isabs(filepath):
        raise NativeCacheError("Save the .blend first, or choose Cache Files: the Alembic file goes beside the cache")
    os.makedirs(os.path.dirname(filepath), exist_ok=True)
    previous = playing_file(obj)
    remove_native_cache(obj)
    view_layer = bpy.context.view_layer
    selection = [other for other in view_layer.objects if other.select_get()]
    active = view_layer.objects.active
    frame = scene.frame_current
    # The exporter writes a mesh without modifiers or animation once, as constant: a modifier that changes nothing
    # makes it sample every frame.
    marker = obj.modifiers.new(MODIFIER_NAME + " (exporting)", "DISPLACE")
    marker.strength = 0.0

    def build_before_evaluation(changed_scene, *_args):
        # The exporter reads the scene as evaluated for each frame, before frame_change_post would rebuild. Forced:
        # a frame shown (or failed) at the same settings before is built again, so its failure is recorded.
        if changed_scene == scene:
            update.update_surface(obj, scene, force=True)

    # Written beside the file and moved over it once complete: a failed export leaves an earlier file whole.
    writing = os.path.splitext(filepath)[0] + ".exporting.abc"
    bpy.app.handlers.frame_change_pre.append(build_before_evaluation)
    try:
        with update.exporting(obj) as record:
            for other in selection:
                other.select_set(False)
            obj.select_set(True)
            view_layer.objects.active = obj
            try:
                result = bpy.ops.wm.alembic_export(filepath=writing, start=frame_start, end=frame_end,
                                                   selected=True, uvs=False, normals=True, face_sets=False,
                                                   export_hair=False, export_particles=False,
                                                   as_background_job=False)
            except RuntimeError as error:  # the exporter's error report (a folder it cannot write, ...)
                result, export_error = {"CANCELLED"}, error
            else:
                export_error = None
    finally:
        bpy.app.handlers.frame_change_pre.remove(build_before_evaluation)
        obj.modifiers.remove(marker)
        obj.select_set(False)
        for other in selection:
            other.select_set(True)
        view_layer.objects.active = active
        scene.frame_set(frame)
    # Empty frames are what Empty Surface asks for; under Stop, or Hold with nothing to hold, the export fails.
    stopped = {failed_frame: reason for failed_frame, (reason, held) in record.failed.items()
               if held is None and obj.meniscus.render_failure != render_policy.EMPTY}
    if stopped or result != {"FINISHED"} or not os.path.exists(writing):
        _abandon(obj, writing, previous)
        if stopped:
            reasons = "; ".join(f"frame {failed_frame}: {reason}" for failed_frame, reason in sorted(stopped.items()))
            raise NativeCacheError(f"Not exported: frames {_frame_list(stopped)} cannot be built ('If a Frame Fails' "
                                   f"is {_policy_label(obj)}; {reasons})")
        raise NativeCacheError(f"Blender's Alembic exporter did not write {filepath}" +
                               (f": {export_error}" if export_error else ""))
    try:
        # Blender keeps an archive open while a cache file data-block reads it (the modifier removed above left
        # one): on Windows the file could not be replaced.
        _release_cache_files(filepath)
        _move_into_place(writing, filepath)
    except OSError as error:
        _abandon(obj, writing, previous)
        raise NativeCacheError(f"Not exported: {filepath} cannot be replaced ({error.strerror or error}); close what "
                               "holds it open (another Blender playing it) and export again") from error
    _play(obj, filepath)
    from_particles = record.built | {frame for frame, (_, held) in record.failed.items() if held is None}
    cube_size = obj.meniscus.render_cube_size if from_particles or not record.from_cache else None
    return ExportResult(filepath, frame_end - frame_start + 1, cube_size, len(record.from_cache),
                        dict(record.failed))


def _move_into_place(writing, filepath):
    """Replaces filepath by the finished export. Windows refuses to rename over a file that a reader opened without
    delete sharing, and Blender keeps a played archive open a while after its data-block is gone: the finished file's
    contents are then written over the old one in place, as the exporter itself would write it. A reader that shares
    no write access either (another program reading the file) is waited for (busy_files.WAIT_SECONDS); then the last
    refusal is raised."""
    def write_over():
        shutil.copyfile(writing, filepath)
        os.remove(writing)
        return True

    busy_files.replace(writing, filepath, otherwise=write_over)


def _abandon(obj, writing, previous):
    """A failed export changes nothing: the partial file goes and the earlier file plays on."""
    if os.path.exists(writing):
        os.remove(writing)
    if previous and os.path.exists(previous):
        _play(obj, previous)


def _release_cache_files(filepath):
    """Removes the cache file data-blocks that read filepath and nothing uses any more (Blender then closes it)."""
    def reads(cache_file):
        path = os.path.abspath(bpy.path.abspath(cache_file.filepath, library=cache_file.library))
        return os.path.normcase(path) == os.path.normcase(filepath)

    unused = [cache_file for cache_file in bpy.data.cache_files if cache_file.users == 0 and reads(cache_file)]
    if unused:  # bpy.data.cache_files has no remove()
        bpy.data.batch_remove(unused)


def _policy_label(obj):
    return next(label for identifier, label, _ in render_policy.ITEMS if identifier == obj.meniscus.render_failure)


def _play(obj, filepath):
    """Adds the Mesh Sequence Cache modifier that plays filepath on obj (through an import, the one way every
    version creates the cache file data-block and knows the path of the mesh inside it)."""
    before = set(bpy.data.objects)
    result = bpy.ops.wm.alembic_import(filepath=filepath, as_background_job=False)
    imported = [other for other in bpy.data.objects if other not in before]
    try:
        source = next((m for other in imported for m in other.modifiers if m.type == "MESH_SEQUENCE_CACHE"), None)
        if result != {"FINISHED"} or source is None:
            raise NativeCacheError(f"Blender could not read back {filepath}")
        modifier = obj.modifiers.new(MODIFIER_NAME, "MESH_SEQUENCE_CACHE")
        # Everything the importer set (cache file, object path, which data to read: 4.5 reads velocities only
        # where the importer asked for them).
        for prop in source.bl_rna.properties:
            if not prop.is_readonly and prop.identifier not in ("name", "show_expanded", "is_active"):
                try:
                    setattr(modifier, prop.identifier, getattr(source, prop.identifier))
                except (AttributeError, TypeError, ValueError):
                    pass
    finally:
        for other in imported:
            mesh = other.data
            bpy.data.objects.remove(other, do_unlink=True)
            if mesh is not None and mesh.users == 0:
                bpy.data.meshes.remove(mesh)
        # The view layer's object list is synced lazily: until then it still holds the removed objects, and a
        # script (or the next export) that walks it reads freed memory (4.5 crashed).
        bpy.context.view_layer.update()
    # The modifier replaces the geometry: the mesh under it is emptied (4.5 would otherwise keep its stale 'velocity'
    # beside the file's, renamed 'velocity.001', and the .blend would carry a frame for nothing).
    mesh_update.clear_surface(obj.data)
    obj.meniscus.use_native_cache = True


def playing_file(obj):
    """The absolute path of the Alembic file the surface plays, or None."""
    modifier = obj.modifiers.get(MODIFIER_NAME)
    cache_file = getattr(modifier, "cache_file", None)
    return bpy.path.abspath(cache_file.filepath, library=cache_file.library) if cache_file else None


def remove_native_cache(obj):
    for modifier in [m for m in obj.modifiers if m.name.startswith(MODIFIER_NAME)]:
        obj.modifiers.remove(modifier)
    obj.meniscus.use_native_cache = False


class MENISCUS_OT_export_alembic(bpy.types.Operator):
    """Write the surface's frames as an Alembic mesh sequence (Blender's own exporter) and play it through a Mesh
    Sequence Cache modifier: the .blend then renders the same frames in a Blender without Meniscus (render farms)"""
    bl_idname = "meniscus.export_alembic"
    bl_label = "Export for Renders Without Meniscus"
    bl_options = {"REGISTER"}

    object_name: bpy.props.StringProperty(name="Object", description="Surface to export (default: the active object)")

    def execute(self, context):
        obj = bpy.data.objects.get(self.object_name) if self.object_name else context.active_object
        scene = context.scene
        try:
            result = export_alembic(obj, scene, scene.frame_start, scene.frame_end)
        except NativeCacheError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.report({"WARNING"} if result.failed else {"INFO"}, summary(result))
        return {"FINISHED"}


class MENISCUS_OT_remove_alembic(bpy.types.Operator):
    """Stop playing the exported Alembic file: the surface is rebuilt by Meniscus again (the file is kept)"""
    bl_idname = "meniscus.remove_alembic"
    bl_label = "Remove Alembic Playback"
    bl_options = {"REGISTER", "UNDO"}

    object_name: bpy.props.StringProperty(name="Object")

    def execute(self, context):
        obj = bpy.data.objects.get(self.object_name) if self.object_name else context.active_object
        if not surfaces.is_surface(obj):
            return {"CANCELLED"}
        remove_native_cache(obj)
        update.update_surface(obj, context.scene, force=True)
        return {"FINISHED"}


classes = (MENISCUS_OT_export_alembic, MENISCUS_OT_remove_alembic)
register, unregister = bpy.utils.register_classes_factory(classes)
