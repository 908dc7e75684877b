"""Export Farm Job: the selected surface's frame range as an Open Job Description job bundle (AWS Deadline Cloud's
`deadline bundle submit`, any OpenJD runner) with its parameters file, and the surface pointed at the job's output
folder, so that it plays the farm's meshes as its cache as they arrive. docs/farm.md."""
import json
import os

import bpy
import numpy as np
from bpy.props import IntProperty, StringProperty

from .. import cache, farm, sequence
from . import bake, paths, update


class FarmExportError(Exception):
    pass


def export_farm_job(obj, bundle_dir, chunk_size=1, meniscus_command="meniscus", scene=None):
    """Writes the job bundle of a surface (the bake's frames, settings and cache folder, as PLY: what the command
    line writes) and switches the surface to play that cache. Returns farm.Bundle."""
    try:
        job, stored = bake.prepare_bake(obj, scene=scene)
    except bake.BakeError as error:
        raise FarmExportError(str(error)) from None
    if any(task.arguments for task in job.tasks):
        raise FarmExportError("The container moves: a farm job holds one box for all frames (bake in Blender instead)")
    settings = obj.meniscus
    stored = os.path.splitext(stored)[0] + cache.FORMAT_EXTENSIONS[cache.PLY]
    output = os.path.normpath(bpy.path.abspath(stored, library=obj.library))
    source = update.available_frames(obj)
    first, last = job.tasks[0].frame, job.tasks[-1].frame
    # The input pattern from the files the bake found: the command line resolves it the same way (frame_pattern).
    pattern = sequence.parse_pattern(source[first]).pattern_string()
    # Blender keeps reals as 32-bit floats (0.025 is 0.0250000004): the job carries the values as the panel shows them.
    parameters = {name: float(np.format_float_positional(np.float32(value), unique=True)) if isinstance(value, float) else value
                  for name, value in job.arguments.items() if name in farm.BY_NAME}
    parameters["threads"] = 0  # the farm host's cores, not this workstation's setting
    try:
        text = farm.parameters_file_text(parameters, input=pattern, output=output, start=first, end=last,
                                         attributes=list(job.wanted_attributes))
    except ValueError as error:
        raise FarmExportError(str(error)) from None
    bundle = farm.write_openjd_bundle(bpy.path.abspath(bundle_dir), text, pattern, output, first, last, chunk_size,
                                      meniscus_command, f"Meniscus {obj.name} {first}-{last}")
    settings.is_surface = False  # several fields change: one rebuild at the end, not one per field
    settings.cache_format = cache.PLY
    settings.cache_pattern = stored
    settings.use_cache = True
    settings.is_surface = True
    update.forget_cached_state()
    return bundle


class MENISCUS_OT_export_farm_job(bpy.types.Operator):
    """Write the surface's frame range as a farm job (an Open Job Description bundle for Deadline Cloud or any
    OpenJD runner, with its parameters file); the surface then plays the job's output folder as its cache"""
    bl_idname = "meniscus.export_farm_job"
    bl_label = "Export Farm Job"
    bl_options = {"REGISTER"}

    object_name: StringProperty(name="Object", description="Surface to export (default: the active object)")
    directory: StringProperty(name="Job Folder", description="Folder the job bundle is written to",
                              default="//meniscus_farm_job", subtype="DIR_PATH",
                              options=paths.BLEND_RELATIVE_OPTIONS)
    chunk_size: IntProperty(name="Frames per Task", description="Contiguous frames each farm task reconstructs",
                            default=5, min=1)
    meniscus_command: StringProperty(name="Command", default="meniscus",
                                     description="The meniscus command on the farm's workers (pip install meniscus)")

    def execute(self, context):
        obj = bpy.data.objects.get(self.object_name) if self.object_name else context.active_object
        if self.directory.startswith("//") and not bpy.data.is_saved:
            self.report({"ERROR"}, "Save the .blend first, or choose a Job Folder: the job goes next to the .blend")
            return {"CANCELLED"}
        try:
            bundle = export_farm_job(obj, self.directory, self.chunk_size, self.meniscus_command, context.scene)
        except FarmExportError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        # What the job will redo (outputs of other parameters) and frames without particle files: said, not hidden.
        with open(bundle.parameters_file, encoding="utf-8") as stream:
            survey = farm.survey_outputs(json.load(stream), bundle.tasks[0][0], bundle.tasks[-1][1])
        notes = "".join(f"; {line}" for line in survey.lines())
        self.report({"WARNING"} if notes else {"INFO"},
                    f"Farm job written to {bundle.directory} ({len(bundle.tasks)} tasks){notes}")
        return {"FINISHED"}

    def invoke(self, context, _event):
        return context.window_manager.invoke_props_dialog(self)


classes = (MENISCUS_OT_export_farm_job,)
register, unregister = bpy.utils.register_classes_factory(classes)
