"""The 'Meniscus' tab of the 3D Viewport sidebar (N panel): add sequences, edit the active surface, see its status."""
import textwrap

import bpy

from .. import sequence
from . import handlers


def _wrap_lines(text, context):
    """Splits text into its lines and wraps long ones to the sidebar's width."""
    region = getattr(context, "region", None)
    # About 8 pixels per character at scale 1, less the icon column: an estimate, on the safe side.
    pixels = (region.width if region else 300) / max(context.preferences.system.ui_scale, 0.1)
    width = max(16, int((pixels - 60) / 8))
    lines = []
    for line in text.split(handlers.STATUS_LINE_SEPARATOR):
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
        return handlers.is_surface(context.active_object)


class MENISCUS_PT_main(_SidebarPanel, bpy.types.Panel):
    bl_label = "Meniscus"

    def draw(self, context):
        layout = self.layout
        layout.operator("meniscus.add_sequence", icon="MOD_FLUIDSIM")
        obj = context.active_object
        if not handlers.is_surface(obj):
            layout.label(text="Select a surface to edit it")
            return
        settings = obj.meniscus
        row = layout.row(align=True)
        row.label(text=obj.name, icon="OUTLINER_OB_MESH")
        row.operator("meniscus.reload", text="", icon="FILE_REFRESH")
        # The status: what the handler did at the last frame (file, particles, triangles, seconds) or the error.
        box = layout.box()
        box.alert = settings.status_is_error
        column = box.column(align=True)
        text = settings.status or "Not built yet"
        # Errors are wrapped so that the whole message (often a path) can be read; the normal status has short lines.
        lines = _wrap_lines(text, context) if settings.status_is_error else text.split(handlers.STATUS_LINE_SEPARATOR)
        for index, line in enumerate(lines):
            icon = ("ERROR" if settings.status_is_error else "INFO") if index == 0 else "BLANK1"
            column.label(text=line, icon=icon)
        if obj.mode == "EDIT":
            layout.label(text="Not updated while in Edit Mode", icon="EDITMODE_HLT")


class MENISCUS_PT_source(_SurfacePanel, bpy.types.Panel):
    bl_label = "Files"

    def draw(self, context):
        layout = self.layout
        # No property split: in a narrow sidebar it cuts the labels down to a few letters.
        obj = context.active_object
        settings = obj.meniscus
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
            frames = handlers.available_frames(obj)
        except Exception:
            frames = {}
        found = sequence.frame_range(frames)
        row = layout.row()
        row.label(text=f"{len(frames)} files, frames {found[0]}-{found[1]}" if found else "No files found",
                  icon="FILE" if found else "ERROR")
        row.operator("meniscus.detect_frame_range", text="", icon="PREVIEW_RANGE")


class MENISCUS_PT_reconstruction(_SurfacePanel, bpy.types.Panel):
    bl_label = "Reconstruction"

    def draw(self, context):
        layout = self.layout
        # No property split: in a narrow sidebar it cuts the labels down to a few letters.
        settings = context.active_object.meniscus
        layout.prop(settings, "particle_radius")
        layout.prop(settings, "smoothing_length")
        layout.prop(settings, "cube_size")
        layout.prop(settings, "iso_threshold")


class MENISCUS_PT_postprocessing(_SurfacePanel, bpy.types.Panel):
    bl_label = "Post-processing"

    def draw(self, context):
        layout = self.layout
        # No property split: in a narrow sidebar it cuts the labels down to a few letters.
        settings = context.active_object.meniscus
        layout.prop(settings, "smoothing_iterations")
        layout.prop(settings, "decimate_barnacles")
        layout.prop(settings, "normal_smoothing_iterations")
        layout.prop(settings, "use_custom_normals")


classes = (MENISCUS_PT_main, MENISCUS_PT_source, MENISCUS_PT_reconstruction, MENISCUS_PT_postprocessing)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
