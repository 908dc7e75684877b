"""The Blender side of Meniscus; the only part of the package that imports bpy.

Laid out like Blender's own add-ons: properties (data, made from the parameter schema), operators and bake
(actions; operators.add_surface_object adds surfaces), farm_export (a farm job for the surface), native_cache (the Alembic export for renders without the
add-on), panels (UI), app_handlers (Blender's frame-change, render, load and undo hooks), update (rebuilding a
surface for the current frame; its frame cache and worker are meniscus.playback), arguments (the pipeline's
arguments from the settings, messages in the panel's words), render_policy (a frame that fails in a render),
surfaces (which objects are surfaces), paths ('//' paths through Save As and moves), render_state, sources (live objects), mesh_update (writing meshes: every
Blender version difference) and material (the default water material). Modules import each other one way only:
properties -> update -> arguments, never back.
"""
from . import app_handlers, bake, farm_export, native_cache, operators, panels, properties

# Registration order matters: panels and operators refer to the properties, handlers use all of them.
_modules = (properties, operators, bake, farm_export, native_cache, panels, app_handlers)
_registered = False


def register():
    global _registered
    if _registered:  # a second register() without unregister() would fail on the already registered classes
        return
    for module in _modules:
        module.register()
    _registered = True


def unregister():
    global _registered
    if not _registered:
        return
    for module in reversed(_modules):
        module.unregister()
    _registered = False
