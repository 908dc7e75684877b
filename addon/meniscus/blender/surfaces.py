"""Surface objects: what makes an object a Meniscus surface, and the one way every operator adds one."""
import bpy

from . import material, properties

STATUS_LINE_SEPARATOR = "\n"  # the status holds one fact per line; the panel shows each on its own row


def is_surface(obj):
    return obj is not None and obj.type == "MESH" and obj.meniscus.is_surface


def surface_objects(scene):
    return [obj for obj in scene.objects if is_surface(obj)]


def add_surface_object(context, name, configure):
    """Adds a surface object to the active collection, selected and active, and builds its current frame.

    configure(settings) fills the object's Meniscus settings before it becomes a surface (until is_surface is set,
    the settings' update callbacks do not rebuild once per field). Returns the object.
    """
    from . import app_handlers, update  # they import this module

    scene = context.scene
    mesh = bpy.data.meshes.new(name)
    obj = bpy.data.objects.new(mesh.name, mesh)
    (context.collection or scene.collection).objects.link(obj)
    material.assign_material(mesh, material.ensure_water_material())
    settings = obj.meniscus
    settings.settings_version = properties.SETTINGS_VERSION
    configure(settings)
    settings.is_surface = True
    # The frame handler edits meshes while a render runs; locking the interface keeps the UI from reading them at
    # the same time (a crash otherwise).
    scene.render.use_lock_interface = True
    app_handlers.ensure_registered()
    update.update_surface(obj, scene, force=True)
    for other in getattr(context, "selected_objects", ()):
        other.select_set(False)
    if context.view_layer.objects.get(obj.name) is not None:
        obj.select_set(True)
        context.view_layer.objects.active = obj
    return obj
