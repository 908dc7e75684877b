"""Blender's application handlers: frame changes, live-source edits, renders, file loads and undo call the updater.
Registered once (re-registration and a reloaded module replace, never duplicate them); persistent across file
loads, where load_post also converts settings saved by older versions."""
import traceback

import bpy
from bpy.app.handlers import persistent

from . import fluid_domain, paths, properties, render_policy, render_state, update
from .surfaces import surface_objects

@persistent
def meniscus_frame_change_post(scene, depsgraph=None):
    try:
        if not render_state.is_rendering():  # frames of surfaces deleted since (scripts may not update the depsgraph)
            update.release_removed_surfaces()
        update.update_scene(scene, depsgraph=depsgraph)
        # In an animation render the next frame is built in the background while Blender renders this one.
        if render_state.is_rendering() and render_state.renders_more_frames():
            update.build_next_render_frame(scene)
    except Exception:  # update_surface never raises; this guards the loop itself (e.g. a scene being freed)
        traceback.print_exc()


@persistent
def meniscus_depsgraph_update_post(scene, depsgraph=None):
    # Live sources change without a frame change too (the user edits the source mesh, a simulation re-bakes):
    # rebuild the surfaces whose source object is among the updated data. Our own mesh writes also land here;
    # they are not sources, and an unchanged source hashes to the same key, so this never loops.
    try:
        if depsgraph is None or render_state.is_rendering():
            return
        # A surface deleted or unlinked: its kept frames go now, not when the next file loads.
        update.release_removed_surfaces()
        updated = {update.id.original for update in depsgraph.updates if isinstance(update.id, bpy.types.Object)}
        if not updated:
            return
        for obj in surface_objects(scene):
            settings = obj.meniscus
            live_source = settings.source_type == "OBJECT" and (
                settings.source_object in updated or fluid_domain.obstacle_among(settings.source_object, updated))
            # A domain's baked frames are checked against the domain as it is now: a change may make them stale.
            baked_domain = settings.use_cache and live_source and fluid_domain.is_liquid_domain(settings.source_object)
            if baked_domain or (not settings.use_cache and (live_source or settings.container_object in updated)):
                update.update_surface(obj, scene, depsgraph=depsgraph)
    except Exception:
        traceback.print_exc()


@persistent
def meniscus_render_init(scene, *_args):
    render_state.set_rendering(True)
    render_policy.forget_failed_frames()
    update.forget_handled_failures()


@persistent
def meniscus_render_write(scene, *_args):
    render_state.note_frame_written()
    # An interactive render cannot be stopped: the image of a frame whose surface failed is set aside once written.
    try:
        render_policy.set_aside_failed_image(scene)
    except Exception:
        traceback.print_exc()


@persistent
def meniscus_render_pre(scene, *_args):
    # A still render (F12) does not change the frame, so the surface still has the viewport cube size: rebuild it
    # with the render settings here, before the render evaluates the scene. In an animation render the frame
    # change has already done so and this finds nothing to do.
    try:
        update.update_scene(scene)
    except Exception:
        traceback.print_exc()


@persistent
def meniscus_render_done(scene, *_args):
    render_state.set_rendering(False)
    update.drop_render_build_ahead()  # a cancelled render's next frame is not wanted any more (bpy-free)
    if bpy.app.background:  # no viewport to restore; the next frame change uses the viewport settings anyway
        return
    # Back to viewport resolution, but on the main thread (this handler may run on the render thread).
    scene_name = scene.name

    def restore_viewport_surfaces():
        try:
            target = bpy.data.scenes.get(scene_name)
            if target is not None:
                update.update_scene(target)
        except Exception:
            traceback.print_exc()
        return None  # once

    bpy.app.timers.register(restore_viewport_surfaces, first_interval=0.1)


def _migrate_all_settings():
    """Settings saved by older versions of the add-on, converted in every object that has them."""
    for obj in bpy.data.objects:
        if obj.type == "MESH" and obj.meniscus.get("is_surface"):
            try:
                properties.migrate_settings(obj.meniscus)
            except Exception:  # a library object is read-only; it keeps its old values
                traceback.print_exc()


@persistent
def meniscus_load_post(*_args):
    # A new file means new meshes: pointers and listings of the previous file mean nothing any more.
    update.forget_cached_state()
    _migrate_all_settings()
    _guarded(paths.after_load)
    _append_once(bpy.app.handlers.frame_change_post, meniscus_frame_change_post)
    _evaluate_loaded_scene()
    _update_current_scene()


def _evaluate_loaded_scene():
    # Since Blender 4.2 an object's world matrix is not saved in the .blend: until the scene is evaluated, a freshly
    # loaded container sits at the origin with identity scale, and the surface would be cut by a wrong box.
    try:
        view_layer = bpy.context.view_layer
        if view_layer is not None:
            view_layer.update()
    except Exception:
        traceback.print_exc()


@persistent
def meniscus_undo_redo_post(*_args):
    # Undo restores parameters, the frame and the meshes as the undo step saved them, which normally agree; the
    # usual check of file and parameters against what each mesh shows (a rebuild only on a mismatch, e.g. a mesh
    # that undo moved in memory) guards the cases where they do not. Paths first: a step from before a Save As holds
    # '//' paths written for the folder the file was in then.
    _guarded(paths.after_undo)
    _update_current_scene()


@persistent
def meniscus_save_pre(filepath=None, *_args):
    # Blender rewrites its own '//' paths for the folder the file goes to; the surfaces' paths follow (see paths).
    _guarded(paths.before_save, filepath)


@persistent
def meniscus_save_post(filepath=None, *_args):
    _guarded(paths.after_save, filepath)


@persistent
def meniscus_save_post_fail(filepath=None, *_args):
    _guarded(paths.after_failed_save, filepath)


def _guarded(function, *arguments):
    # Inside a save or a load: a failure is printed, never raised into Blender.
    try:
        function(*arguments)
    except Exception:
        traceback.print_exc()


def _update_current_scene():
    # A handler must not raise into Blender: a failure is printed, the surfaces keep what they show.
    try:
        scene = bpy.context.scene
        if scene is not None:
            update.update_scene(scene)
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
    # A failed save runs no save_post: 4.2+ tell it apart (3.4 rewrites no path before it writes, see paths).
    save_failed = ((handlers.save_post_fail, meniscus_save_post_fail),) if hasattr(handlers, "save_post_fail") else ()
    return save_failed + ((handlers.frame_change_post, meniscus_frame_change_post),
            (handlers.depsgraph_update_post, meniscus_depsgraph_update_post),
            (handlers.render_init, meniscus_render_init),
            (handlers.render_pre, meniscus_render_pre),
            (handlers.render_write, meniscus_render_write),
            (handlers.render_complete, meniscus_render_done),
            (handlers.render_cancel, meniscus_render_done),
            (handlers.load_post, meniscus_load_post),
            (handlers.save_pre, meniscus_save_pre),
            (handlers.save_post, meniscus_save_post),
            (handlers.undo_post, meniscus_undo_redo_post),
            (handlers.redo_post, meniscus_undo_redo_post))


def register():
    for handler_list, function in _handler_slots():
        _append_once(handler_list, function)


def unregister():
    for handler_list, function in _handler_slots():
        _remove_ours(handler_list, function)
    update.forget_cached_state()
    update.stop_background_work()
    render_state.set_rendering(False)
