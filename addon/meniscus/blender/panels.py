"""The 'Meniscus' tab of the 3D Viewport sidebar (N panel): add sequences, edit the active surface, see its status."""
import textwrap

import bpy

from .. import parameters, sequence
from . import bake, fluid_domain, properties, surfaces, update


def status_width(context):
    """Characters of a label that fit the sidebar: about 8 pixels each at scale 1, less the icon column (an
    estimate, on the safe side)."""
    region = getattr(context, "region", None)
    pixels = (region.width if region else 300) / max(context.preferences.system.ui_scale, 0.1)
    return max(16, int((pixels - 60) / 8))


def _shorten_word(word, width):
    # A file name longer than the sidebar loses its middle, not its end: the frame number stays visible.
    if len(word) <= width:
        return word
    head = max(3, width // 4)
    return word[:head] + "\u2026" + word[-(width - head - 1):]


def _wrap_lines(text, context, whole_words=False):
    """Splits text into its lines and wraps long ones to the sidebar's width. whole_words: a word longer than a line
    is shortened in its middle instead of being cut across lines."""
    width = status_width(context)
    lines = []
    for line in text.split(surfaces.STATUS_LINE_SEPARATOR):
        if whole_words:
            line = " ".join(_shorten_word(word, width) for word in line.split(" "))
        lines.extend(textwrap.wrap(line, width) or [""])
    return lines


class _SidebarPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Meniscus"


class _SurfacePanel(_SidebarPanel):
    """Sub-panels shown only while the active object is a Meniscus surface."""
    bl_parent_id = "MENISCUS_PT_main"

    @classmethod
    def poll(cls, context):
        return surfaces.is_surface(context.active_object)


class MENISCUS_PT_main(_SidebarPanel, bpy.types.Panel):
    bl_label = "Meniscus"

    def draw(self, context):
        layout = self.layout
        # One button a row: at the sidebar's default width two side by side lose their labels.
        column = layout.column(align=True)
        column.operator("meniscus.add_sequence", text="Add Particle Sequence", icon="MOD_FLUIDSIM")
        column.operator("meniscus.add_cache", text="Add Mesh Cache", icon="FILE_CACHE")
        column.operator("meniscus.add_object_surface", icon="PARTICLES")
        column.operator("meniscus.add_fluid_domain_surface", icon="MOD_FLUIDSIM")
        obj = context.active_object
        if not surfaces.is_surface(obj):
            layout.label(text="Select a surface to edit it")
            return
        settings = obj.meniscus
        # The surface's name on a row of its own (beside a button it is cut to a few letters), then the re-run
        # button: rebuilds the current frame from scratch (also after files changed on disk).
        layout.label(text=obj.name, icon="OUTLINER_OB_MESH")
        layout.operator("meniscus.reload", text="Rebuild", icon="FILE_REFRESH")
        # The status: what the handler did at the last frame (file, particles, triangles, seconds) or the error.
        box = layout.box()
        box.alert = settings.status_is_error
        column = box.column(align=True)
        text = settings.status or "Not built yet"
        # Wrapped to the sidebar's width: errors (often a path) are read whole, and a long file name cannot hide the
        # frame number at its end.
        lines = _wrap_lines(text, context, whole_words=not settings.status_is_error)
        for index, line in enumerate(lines):
            icon = ("ERROR" if settings.status_is_error else "INFO") if index == 0 else "BLANK1"
            column.label(text=line, icon=icon)
        if settings.use_cache:
            # Baked frames of other settings are rebuilt from the particles (update._stale_cache_frame), not played.
            layout.label(text="Playing from cache: frames baked otherwise are rebuilt", icon="FILE_CACHE")
        if obj.mode == "EDIT":
            layout.label(text="Not updated while in Edit Mode", icon="EDITMODE_HLT")


class MENISCUS_PT_source(_SurfacePanel, bpy.types.Panel):
    bl_label = "Source"

    def draw(self, context):
        layout = self.layout
        # No property split: in a narrow sidebar it cuts the labels down to a few letters.
        obj = context.active_object
        settings = obj.meniscus
        layout.prop(settings, "source_type", expand=True)
        if settings.source_type == "OBJECT":
            layout.prop(settings, "source_object", text="Object")
            if fluid_domain.is_liquid_domain(settings.source_object):
                column = layout.column(align=True)
                for line in fluid_domain.describe(settings.source_object):
                    column.label(text=line)
            return
        layout.prop(settings, "file_pattern", text="Files")

        col = layout.column(align=True)
        col.prop(settings, "frame_start", text="Frame Start")
        col.prop(settings, "frame_end", text="Frame End")
        layout.prop(settings, "frame_offset")
        row = layout.row()
        row.label(text="Outside Range")
        row.prop(settings, "out_of_range", text="")

        # Cheap to draw: the listing is cached and only re-read when the folder changes.
        try:
            frames = update.available_frames(obj)
        except Exception:
            frames = {}
        found = sequence.frame_range(frames)
        row = layout.row()
        row.label(text=f"{len(frames)} files, frames {found[0]}-{found[1]}" if found else "No files found",
                  icon="FILE" if found else "ERROR")
        row.operator("meniscus.detect_frame_range", text="", icon="PREVIEW_RANGE")


class MENISCUS_PT_cache(_SurfacePanel, bpy.types.Panel):
    bl_label = "Bake & Cache"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        obj = context.active_object
        settings = obj.meniscus
        layout.prop(settings, "cache_pattern", text="Cache")
        if not settings.cache_pattern:
            layout.label(text="Default: " + update.cache_pattern_string(obj), icon="BLANK1")
        layout.prop(settings, "cache_format", text="Format")
        job = bake.job_for(obj)
        if job is not None:
            text = f"Baking {job.completed}/{job.total}"
            if hasattr(layout, "progress"):  # 4.0+: a real progress bar in the panel
                layout.progress(factor=job.progress, type="BAR", text=text)
            else:
                layout.label(text=text, icon="TIME")
            layout.operator("meniscus.bake_cancel", text="Cancel", icon="CANCEL").object_name = obj.name
        else:
            row = layout.row()
            row.enabled = settings.source_type == "FILES" or fluid_domain.is_liquid_domain(settings.source_object)
            row.operator("meniscus.bake", text="Bake Frame Range", icon="RENDER_ANIMATION").object_name = obj.name
            # The same frames on a render farm: a job bundle and its parameters file; the surface then plays its output.
            row = layout.row()
            row.enabled = settings.source_type == "FILES"
            row.operator("meniscus.export_farm_job", text="Export Farm Job", icon="NETWORK_DRIVE").object_name = obj.name
        row = layout.row()
        row.enabled = settings.use_cache or update.has_cache_frames(obj)  # nothing baked: nothing to play
        row.prop(settings, "use_cache")
        # Renders on machines without the add-on: the frames as an Alembic file that Blender plays by itself.
        if settings.use_native_cache:
            layout.label(text="Plays its Alembic file (no Meniscus needed)", icon="CHECKMARK")
            layout.operator("meniscus.remove_alembic", icon="X").object_name = obj.name
        else:
            layout.operator("meniscus.export_alembic", icon="EXPORT").object_name = obj.name


def _is_on(settings, name):
    """Whether a parameter is on (non-zero): a dependent parameter only matters then (or only while it is off)."""
    if name == "normals":
        return settings.use_custom_normals
    return bool(getattr(settings, name))


def draw_parameters(layout, settings, group):
    """Every schema parameter of a group, in schema order: greyed out while the parameter it depends on is off, and
    with its Automatic switch where it has one. A parameter added to the schema appears here by itself."""
    for parameter in parameters.PARAMETERS:
        if parameter.group != group or parameter.name in properties.DRIVEN_BY_ADDON or parameter.type == "vector3":
            continue
        column = layout.column(align=True)
        column.active = parameter.matters(lambda name: _is_on(settings, name))
        if parameter.automatic is not None:
            # [Neighbour Count 5.00][Auto], the switch narrow so that the label keeps its words.
            row = column.split(factor=0.72, align=True)
            if getattr(settings, parameter.name + "_auto"):
                # What Auto means here, not the greyed manual value, which it ignores; the meaning on a row of its
                # own ("75 % of 31.2 GiB" beside a label does not fit the default sidebar).
                row.label(text=parameter.label + ":")
                row.prop(settings, parameter.name + "_auto", text="Auto", toggle=True)
                column.label(text=properties.automatic_meaning(parameter.name), icon="BLANK1")
            else:
                row.prop(settings, parameter.name)
                row.prop(settings, parameter.name + "_auto", text="Auto", toggle=True)
        else:
            column.prop(settings, parameter.name)


class _ParameterPanel(_SurfacePanel):
    """A sub-panel for one group of the parameter schema, plus the add-on's own settings that belong there."""
    group = ""

    def draw(self, context):
        settings = context.active_object.meniscus
        self.draw_before(self.layout, settings)
        draw_parameters(self.layout, settings, self.group)
        self.draw_after(self.layout, settings)

    def draw_before(self, layout, settings):
        pass

    def draw_after(self, layout, settings):
        pass


class MENISCUS_PT_reconstruction(_ParameterPanel, bpy.types.Panel):
    bl_label = "Surface"
    group = "surface"

    def draw_after(self, layout, settings):
        col = layout.column(align=True)
        col.prop(settings, "cube_size")
        col.prop(settings, properties.RENDER_CUBE_SIZE)
        column = layout.column(align=True)  # the label above its menu: beside it, it is cut to "If a Fr..."
        column.label(text="If a Frame Fails:")
        column.prop(settings, "render_failure", text="")


class MENISCUS_PT_smoothing(_ParameterPanel, bpy.types.Panel):
    bl_label = "Smoothing"
    group = "smoothing"


class MENISCUS_PT_container(_ParameterPanel, bpy.types.Panel):
    bl_label = "Container"
    bl_options = {"DEFAULT_CLOSED"}
    group = "container"

    def draw_before(self, layout, settings):
        layout.prop(settings, "container_object")
        row = layout.row()
        row.active = settings.container_object is not None
        row.prop(settings, "use_container_particle_box")


class MENISCUS_PT_mesh(_ParameterPanel, bpy.types.Panel):
    bl_label = "Mesh Cleanup"
    bl_options = {"DEFAULT_CLOSED"}
    group = "mesh"


class MENISCUS_PT_normals(_ParameterPanel, bpy.types.Panel):
    bl_label = "Normals"
    bl_options = {"DEFAULT_CLOSED"}
    group = "normals"

    def draw_before(self, layout, settings):
        layout.prop(settings, "use_custom_normals")


class MENISCUS_PT_attributes(_ParameterPanel, bpy.types.Panel):
    bl_label = "Attributes"
    bl_options = {"DEFAULT_CLOSED"}
    group = "output"

    def draw_after(self, layout, settings):
        layout.prop(settings, "attribute_names")
        layout.label(text="Read them with an Attribute node", icon="NODE")


class MENISCUS_PT_performance(_ParameterPanel, bpy.types.Panel):
    bl_label = "Performance"
    bl_options = {"DEFAULT_CLOSED"}
    group = "execution"


classes = (MENISCUS_PT_main, MENISCUS_PT_source, MENISCUS_PT_cache, MENISCUS_PT_reconstruction,
           MENISCUS_PT_smoothing, MENISCUS_PT_container, MENISCUS_PT_mesh, MENISCUS_PT_normals, MENISCUS_PT_attributes,
           MENISCUS_PT_performance)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
