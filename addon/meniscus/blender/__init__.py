"""The Blender side of Meniscus; the only part of the package that imports bpy.

Laid out like Blender's own add-ons: properties (data), operators (actions), panels (UI), handlers (frame change),
plus mesh_update (writing meshes, version differences) and material (the default water material).
"""
from . import bake, handlers, operators, panels, properties

# Registration order matters: panels and operators refer to the properties, handlers use all of them.
_modules = (properties, operators, bake, panels, handlers)
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
