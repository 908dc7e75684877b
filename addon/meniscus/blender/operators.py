"""Operators: add a particle sequence as a surface object, reload surfaces, reset a frame range from the files."""
import os

import bpy
from bpy.props import BoolProperty, FloatProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

from .. import sequence
from . import app_handlers, fluid_domain, material, properties, surfaces, update

# The formats the core reads (each also gzip-compressed), for the file browser's filter.
PARTICLE_FILE_GLOB = "*.vtk;*.vtu;*.vtp;*.bgeo;*.bhclassic;*.ply;*.npy;*.npz;*.csv;*.xyz;*.gz;*.uni;*.vdb"


def add_surface_object(context, name, configure):
    """Adds a surface object to the active collection, selected and active, and builds its current frame.

    configure(settings) fills the object's Meniscus settings before it becomes a surface (until is_surface is set,
    the settings' update callbacks do not rebuild once per field). Returns the object.
    """
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


def _object_name(pattern):
    # 'double_dam_break_' -> 'double_dam_break': the prefix names the sequence without its separator.
    name = pattern.prefix.rstrip("_-. ")
    return name or "Fluid Surface"


def stored_path(pattern_string, make_relative):
    """The path to keep in the object's property: relative to the .blend where possible and wanted."""
    # An unsaved file has no folder to be relative to, so the path stays absolute until the user saves and re-adds.
    if make_relative and bpy.data.is_saved:
        try:
            return bpy.path.relpath(pattern_string)
        except ValueError:  # another drive on Windows: no relative path exists
            pass
    return pattern_string


def find_sequence(operator, filepath, what):
    """The frame pattern of a chosen file, its frames and their range, or None after reporting why there are none.

    what names the files in the message ("particle files", "mesh files").
    """
    absolute = os.path.abspath(bpy.path.abspath(filepath))
    try:
        pattern = sequence.parse_pattern(absolute)
    except ValueError as error:
        operator.report({"ERROR"}, str(error))
        return None
    frames = pattern.list_frames()
    if not frames:
        operator.report({"ERROR"}, f"No {what} match {pattern.pattern_string()}")
        return None
    first, last = sequence.frame_range(frames)
    return pattern, frames, first, last


class MENISCUS_OT_add_sequence(bpy.types.Operator, ImportHelper):
    """Add a fluid surface object that is rebuilt from a sequence of particle files on every frame"""
    bl_idname = "meniscus.add_sequence"
    bl_label = "Add Particle Sequence"
    bl_options = {"REGISTER", "UNDO"}

    # ImportHelper provides `filepath` (a file of the sequence, or a pattern with #### or {} from scripts).
    filename_ext = ""
    filter_glob: StringProperty(default=PARTICLE_FILE_GLOB, options={"HIDDEN"})
    relative_path: BoolProperty(
        name="Relative Path",
        description="Store the path relative to the .blend file (once it is saved)",
        default=True,
    )
    particle_radius: FloatProperty(
        name="Particle Radius",
        description="Radius of one particle in scene units; the other lengths are multiples of it",
        default=0.025, min=1e-6, soft_min=1e-4, soft_max=1.0, precision=4, step=0.1, subtype="DISTANCE", unit="LENGTH",
    )
    use_scene_frame_range: BoolProperty(
        name="Set Scene Frame Range",
        description="Set the scene's start and end frames to the frames found on disk (minus the surface's "
                    "frame offset)",
        default=True,
    )

    def execute(self, context):
        text = self.filepath
        if not text:
            self.report({"ERROR"}, "No file given")
            return {"CANCELLED"}
        found = find_sequence(self, text, "particle files")
        if found is None:
            return {"CANCELLED"}
        pattern, frames, first, last = found

        scene = context.scene
        stored = stored_path(pattern.pattern_string(), self.relative_path)

        def configure(settings):
            settings.file_pattern = stored
            settings.particle_radius = self.particle_radius
            settings.frame_start = first
            settings.frame_end = last

        if self.use_scene_frame_range:
            scene.frame_start, scene.frame_end = first, last
        obj = add_surface_object(context, _object_name(pattern), configure)
        settings = obj.meniscus
        status = settings.status.replace(surfaces.STATUS_LINE_SEPARATOR, ", ")
        self.report({"INFO"}, f"Added '{obj.name}': {len(frames)} frames ({first}-{last}). {status}")
        return {"FINISHED"}


class MENISCUS_OT_reload(bpy.types.Operator):
    """Re-read the particle files and rebuild the surfaces at the current frame (after files changed on disk)"""
    bl_idname = "meniscus.reload"
    bl_label = "Reload Surfaces"
    bl_options = {"REGISTER"}

    all_surfaces: BoolProperty(
        name="All Surfaces",
        description="Reload every surface of the scene, not only the selected ones",
        default=False,
    )

    def execute(self, context):
        update.forget_cached_state()
        scene = context.scene
        if self.all_surfaces:
            targets = surfaces.surface_objects(scene)
        else:
            targets = [obj for obj in context.selected_objects if surfaces.is_surface(obj)]
            active = context.active_object
            if surfaces.is_surface(active) and active not in targets:
                targets.append(active)
        for obj in targets:
            update.update_surface(obj, scene, force=True)
        self.report({"INFO"}, f"Reloaded {len(targets)} surface(s)")
        return {"FINISHED"}


class MENISCUS_OT_detect_frame_range(bpy.types.Operator):
    """Set Start and End of the active surface to the first and last frame found on disk"""
    bl_idname = "meniscus.detect_frame_range"
    bl_label = "Detect Frame Range"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return surfaces.is_surface(context.active_object)

    def execute(self, context):
        obj = context.active_object
        try:
            frames = update.available_frames(obj)
        except update.SurfaceError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        found = sequence.frame_range(frames)
        if found is None:
            self.report({"ERROR"}, "No particle files found")
            return {"CANCELLED"}
        settings = obj.meniscus
        # Paused while both ends change: in between, the range could be empty and each write would rebuild.
        settings.is_surface = False
        settings.frame_start, settings.frame_end = found
        settings.is_surface = True
        update.update_surface(obj, context.scene)
        self.report({"INFO"}, f"Frames {found[0]}-{found[1]} ({len(frames)} files)")
        return {"FINISHED"}


class MENISCUS_OT_add_object_surface(bpy.types.Operator):
    """Add a fluid surface around the particles of the active object (its particle systems, point cloud points or
    mesh vertices), rebuilt as the object changes: surfaces a simulation made in Blender"""
    bl_idname = "meniscus.add_object_surface"
    bl_label = "Surface From Object"
    bl_options = {"REGISTER", "UNDO"}

    DEFAULT_RADIUS = 0.025
    source_name: StringProperty(name="Source", description="Object to surface (default: the active object)")
    particle_radius: FloatProperty(
        name="Particle Radius",
        description="Radius of one particle in scene units; the other lengths are multiples of it (a liquid "
                    "domain's default comes from its grid)",
        default=DEFAULT_RADIUS, min=1e-6, soft_min=1e-4, soft_max=1.0, precision=4, step=0.1, subtype="DISTANCE", unit="LENGTH",
    )

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type in {"MESH", "POINTCLOUD"} and not surfaces.is_surface(obj)

    def execute(self, context):
        source = bpy.data.objects.get(self.source_name) if self.source_name else context.active_object
        if source is None or source.type not in {"MESH", "POINTCLOUD"}:
            self.report({"ERROR"}, "Choose a mesh or point cloud object (particle systems live on meshes)")
            return {"CANCELLED"}
        # A liquid domain's radius comes from its grid unless the caller gave one.
        radius = self.particle_radius if self.properties.is_property_set("particle_radius") else None
        obj = add_object_surface(context, source, radius)
        self.report({"INFO"}, f"Added '{obj.name}'")
        return {"FINISHED"}


def add_object_surface(context, source, particle_radius=None):
    """A surface around another object's particles; a liquid domain's defaults are derived from its grid."""
    def configure(settings):
        settings.source_type = "OBJECT"
        settings.source_object = source
        if fluid_domain.is_liquid_domain(source):
            fluid_domain.configure_surface(settings, source)
        if particle_radius is not None or not fluid_domain.is_liquid_domain(source):
            settings.particle_radius = particle_radius or MENISCUS_OT_add_object_surface.DEFAULT_RADIUS

    return add_surface_object(context, f"{source.name} Surface", configure)


class MENISCUS_OT_add_fluid_domain_surface(bpy.types.Operator):
    """Add a fluid surface around the liquid of a Mantaflow fluid domain (the active one, or the scene's only one),
    read from its cache at each frame: radius and iso threshold derived from the domain's grid"""
    bl_idname = "meniscus.add_fluid_domain_surface"
    bl_label = "Surface From Fluid Domain"
    bl_options = {"REGISTER", "UNDO"}

    hide_domain_in_renders: BoolProperty(
        name="Hide Domain in Renders",
        description="Also hide the domain object (its box or Mantaflow's own mesh) from renders; the surface reads "
                    "the cache, so it is unaffected",
        default=False,
    )

    @classmethod
    def poll(cls, context):
        return fluid_domain.liquid_domain_for(context) is not None

    def execute(self, context):
        domain = fluid_domain.liquid_domain_for(context)
        if domain is None:
            self.report({"ERROR"}, "Select a liquid fluid domain (Physics > Fluid > Domain, type Liquid)")
            return {"CANCELLED"}
        obj = add_object_surface(context, domain)
        if self.hide_domain_in_renders:
            domain.hide_render = True
        self.report({"INFO"}, f"Added '{obj.name}' from the fluid cache of '{domain.name}'")
        return {"FINISHED"}


classes = (MENISCUS_OT_add_sequence, MENISCUS_OT_reload, MENISCUS_OT_detect_frame_range,
           MENISCUS_OT_add_object_surface, MENISCUS_OT_add_fluid_domain_surface)


def menu_import(self, context):
    self.layout.operator(MENISCUS_OT_add_sequence.bl_idname, text="Meniscus Particle Sequence (.vtk, .bgeo, ...)")


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
