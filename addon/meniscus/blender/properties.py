"""Per-object settings of a Meniscus surface: `Object.meniscus`.

Every object that carries `meniscus.is_surface = True` owns one Mesh that the frame handler rebuilds from the
particle file of the current frame. The reconstruction parameters use splashsurf's names and conventions
(lengths other than the radius are multiples of it) so that values carry over between the two tools.
"""
import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from .. import sequence


def _rebuild_after_edit(settings, context):
    # Editing a parameter in the UI should show its effect at once, not at the next frame change. The import is
    # local because handlers imports this module (for the settings' type) and the cycle is harmless only at call time.
    from . import handlers

    if not settings.is_surface:  # the add operator fills many fields before it turns the object into a surface
        return
    scene = getattr(context, "scene", None) or bpy.context.scene
    if scene is not None:
        handlers.update_surface(settings.id_data, scene)


_OUT_OF_RANGE_ITEMS = [
    (sequence.HOLD, "Hold", "Show the first frame before the range and the last frame after it"),
    (sequence.LOOP, "Loop", "Repeat the range"),
    (sequence.BLANK, "Blank", "Show nothing outside the range"),
]


class MeniscusSurfaceSettings(bpy.types.PropertyGroup):
    is_surface: BoolProperty(
        name="Meniscus Surface",
        description="This object's mesh is rebuilt from particle files on every frame change",
        default=False,
        options=set(),  # not animatable: toggling it per frame would make no sense
    )

    # Source ------------------------------------------------------------------------------------------------------
    file_pattern: StringProperty(
        name="Files",
        description="Particle files of the sequence: a file of it (fluid_0001.vtk) or a pattern with #### (padded) or "
                    "{} (unpadded) in place of the frame number. Paths starting with // are relative to the .blend",
        subtype="FILE_PATH",
        options=set(),
        update=_rebuild_after_edit,
    )
    frame_offset: IntProperty(
        name="Frame Offset",
        description="Added to the scene frame to get the file frame number (file frame = scene frame + offset)",
        default=0,
        options=set(),
        update=_rebuild_after_edit,
    )
    frame_start: IntProperty(
        name="Start",
        description="First file frame number of the range that is played",
        default=0,
        options=set(),
        update=_rebuild_after_edit,
    )
    frame_end: IntProperty(
        name="End",
        description="Last file frame number of the range that is played",
        default=0,
        options=set(),
        update=_rebuild_after_edit,
    )
    out_of_range: EnumProperty(
        name="Outside Range",
        description="What to show when the file frame falls outside Start..End",
        items=_OUT_OF_RANGE_ITEMS,
        default=sequence.HOLD,
        options=set(),
        update=_rebuild_after_edit,
    )

    # Reconstruction ----------------------------------------------------------------------------------------------
    particle_radius: FloatProperty(
        name="Particle Radius",
        description="Radius of one particle, in scene units (absolute)",
        default=0.025, min=1e-6, soft_min=1e-4, soft_max=1.0, precision=4, step=0.1,
        subtype="DISTANCE", unit="LENGTH",
        options=set(),
        update=_rebuild_after_edit,
    )
    smoothing_length: FloatProperty(
        name="Smoothing Length",
        description="Kernel smoothing length, as a multiple of the particle radius "
                    "(the kernel reaches 2 x this x radius)",
        default=2.0, min=0.1, soft_min=1.0, soft_max=4.0, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )
    cube_size: FloatProperty(
        name="Cube Size",
        description="Marching-cubes cell size, as a multiple of the particle radius (smaller: finer and slower)",
        default=0.5, min=0.05, soft_min=0.2, soft_max=2.0, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )
    iso_threshold: FloatProperty(
        name="Iso Threshold",
        description="Level of the normalised density at which the surface lies",
        default=0.6, min=0.01, max=5.0, soft_max=1.5, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )

    # Post-processing ---------------------------------------------------------------------------------------------
    smoothing_iterations: IntProperty(
        name="Smoothing Iterations",
        description="Feature-preserving Laplacian smoothing passes on the surface (0: off)",
        default=25, min=0, soft_max=100,
        options=set(),
        update=_rebuild_after_edit,
    )
    decimate_barnacles: BoolProperty(
        name="Remove Barnacles",
        description="Collapse the small bumps (\"barnacles\") that marching cubes leaves on flat fluid surfaces",
        default=True,
        options=set(),
        update=_rebuild_after_edit,
    )
    normal_smoothing_iterations: IntProperty(
        name="Normal Smoothing",
        description="Smoothing passes over the vertex normals (0: off)",
        default=10, min=0, soft_max=50,
        options=set(),
        update=_rebuild_after_edit,
    )
    use_custom_normals: BoolProperty(
        name="Custom Normals",
        description="Use the reconstructed (smoothed) normals for shading instead of Blender's own. Costs time at "
                    "every frame change on large meshes; when off, Blender's smooth shading is used",
        default=True,
        options=set(),
        update=_rebuild_after_edit,
    )

    # Feedback (written by the frame handler) ---------------------------------------------------------------------
    status: StringProperty(
        name="Status",
        description="Outcome of the last rebuild",
        default="",
        options=set(),
    )
    status_is_error: BoolProperty(
        name="Status Is Error",
        default=False,
        options=set(),
    )


classes = (MeniscusSurfaceSettings,)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Object.meniscus = bpy.props.PointerProperty(type=MeniscusSurfaceSettings)


def unregister():
    # The attribute goes first: it references the class that is unregistered next.
    if hasattr(bpy.types.Object, "meniscus"):
        del bpy.types.Object.meniscus
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
