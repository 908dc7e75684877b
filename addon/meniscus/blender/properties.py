"""Per-object settings of a Meniscus surface: `Object.meniscus`.

Every object that carries `meniscus.is_surface = True` owns one Mesh that the frame handler rebuilds from the
particle file of the current frame. The reconstruction parameters use splashsurf's names and conventions
(lengths other than the radius are multiples of it) so that values carry over between the two tools.
"""
import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

from .. import cache, sequence


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


def _can_be_source(settings, obj):
    # A surface fed by its own vertices would rebuild from what it just built; other surfaces are allowed.
    # Particle systems live on mesh objects, so MESH covers them too.
    return obj != settings.id_data and obj.type in {"MESH", "POINTCLOUD"}


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

    source_type: EnumProperty(
        name="Source",
        description="Where the particles come from",
        items=[
            ("FILES", "Particle Files", "A sequence of particle files on disk, one per frame"),
            ("OBJECT", "Object", "The particles of another object in this scene, as it is at the current frame: "
                                 "its particle systems, its points (point cloud) or its mesh vertices"),
        ],
        default="FILES",
        options=set(),
        update=_rebuild_after_edit,
    )
    source_object: PointerProperty(
        name="Source Object",
        description="Object whose particles (particle systems, point cloud points or mesh vertices) are surfaced",
        type=bpy.types.Object,
        poll=_can_be_source,
        options=set(),
        update=_rebuild_after_edit,
    )

    # Cache -------------------------------------------------------------------------------------------------------
    use_cache: BoolProperty(
        name="Play From Cache",
        description="Load the baked meshes instead of reconstructing: scrubbing and rendering only read files",
        default=False,
        options=set(),
        update=_rebuild_after_edit,
    )
    cache_pattern: StringProperty(
        name="Cache Files",
        description="Mesh files of the cache, one per frame: a file of it or a pattern with #### or {} for the frame "
                    "number (.npz baked here, or .ply written by the meniscus command line). Empty: a folder "
                    "'meniscus_cache' next to the .blend",
        subtype="FILE_PATH",
        options=set(),
        update=_rebuild_after_edit,
    )
    cache_format: EnumProperty(
        name="Cache Format",
        description="File format a bake writes (the cache files' extension follows it)",
        items=[
            (cache.NPZ, "NPZ", "Numpy arrays: loads several times faster than PLY (recommended)"),
            (cache.PLY, "PLY", "Binary PLY with normals and attributes: readable by other programs"),
        ],
        default=cache.NPZ,
        options=set(),
    )

    # Reconstruction ----------------------------------------------------------------------------------------------
    particle_radius: FloatProperty(
        name="Particle Radius",
        description="Radius of one particle, in scene units. The other lengths are multiples of it",
        default=0.025, min=1e-6, soft_min=1e-4, soft_max=1.0, precision=4, step=0.1,
        subtype="DISTANCE", unit="LENGTH",
        options=set(),
        update=_rebuild_after_edit,
    )
    smoothing_length: FloatProperty(
        name="Smoothing Length",
        description="How far each particle's influence reaches, in particle radii (it reaches 2 x this x radius). "
                    "Larger: blobbier, fewer holes; smaller: more detail, more holes",
        default=2.0, min=0.1, soft_min=1.0, soft_max=4.0, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )
    cube_size: FloatProperty(
        name="Viewport Cube Size",
        description="Size of the surface's cells in the viewport, in particle radii. Larger is coarser and faster; "
                    "keep it large for scrubbing",
        default=1.0, min=0.05, soft_min=0.2, soft_max=3.0, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )
    render_cube_size: FloatProperty(
        name="Render Cube Size",
        description="Size of the surface's cells in renders and bakes, in particle radii. Smaller gives a finer "
                    "surface and more triangles (halving it means about four times as many)",
        default=0.5, min=0.05, soft_min=0.2, soft_max=3.0, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )
    iso_threshold: FloatProperty(
        name="Iso Threshold",
        description="Where the surface lies, as a fraction of the fluid's density: higher pulls the surface in "
                    "(thinner splashes), lower pushes it out (fuller, more merged drops)",
        default=0.6, min=0.01, max=5.0, soft_max=1.5, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )

    # Smoothing ---------------------------------------------------------------------------------------------------
    smoothing_iterations: IntProperty(
        name="Smoothing Iterations",
        description="How many times the surface is smoothed: removes the bumps of individual particles. "
                    "0 turns smoothing off; 25 is a good start",
        default=25, min=0, soft_max=100,
        options=set(),
        update=_rebuild_after_edit,
    )
    smoothing_strength: FloatProperty(
        name="Smoothing Strength",
        description="How far each smoothing step moves a vertex towards its neighbours (1: all the way)",
        default=1.0, min=0.0, max=1.0, precision=2,
        subtype="FACTOR",
        options=set(),
        update=_rebuild_after_edit,
    )
    use_feature_weights: BoolProperty(
        name="Keep Splashes",
        description="Smooth flat water fully but thin splashes and drops less, so they keep their shape "
                    "(feature weights from the particle neighbourhood)",
        default=True,
        options=set(),
        update=_rebuild_after_edit,
    )
    weights_normalization_auto: BoolProperty(
        name="Automatic Normalisation",
        description="Measure how many neighbours a particle at a flat surface has, per frame, instead of using "
                    "a fixed number",
        default=True,
        options=set(),
        update=_rebuild_after_edit,
    )
    weights_normalization: FloatProperty(
        name="Neighbour Count",
        description="Distance-weighted neighbour count expected at a flat surface: places with fewer neighbours are "
                    "treated as splash and smoothed less. About 5 suits SPH data at rest density with the default "
                    "smoothing length (splashsurf's 13 counts neighbours differently and does not apply here)",
        default=5.0, min=0.1, soft_min=1.0, soft_max=20.0, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )
    volume_restoration: BoolProperty(
        name="Keep Volume",
        description="Push the smoothed surface back out so that smoothing does not shrink the water",
        default=True,
        options=set(),
        update=_rebuild_after_edit,
    )

    # Mesh --------------------------------------------------------------------------------------------------------
    decimate_barnacles: BoolProperty(
        name="Remove Barnacles",
        description="Collapse the small bumps (\"barnacles\") that marching cubes leaves on flat water",
        default=True,
        options=set(),
        update=_rebuild_after_edit,
    )
    mesh_cleanup: BoolProperty(
        name="Mesh Cleanup",
        description="Merge the tiny, thin triangles that marching cubes makes: fewer triangles, better shading",
        default=False,
        options=set(),
        update=_rebuild_after_edit,
    )
    use_snap_distance: BoolProperty(
        name="Limit Snapping",
        description="Clean up only vertices close to a grid point (otherwise every vertex may be merged)",
        default=False,
        options=set(),
        update=_rebuild_after_edit,
    )
    mesh_cleanup_snap_distance: FloatProperty(
        name="Snap Distance",
        description="How close to a grid point a vertex must be to be merged, as a fraction of the cube size",
        default=0.5, min=0.0, max=1.0, precision=2,
        subtype="FACTOR",
        options=set(),
        update=_rebuild_after_edit,
    )

    # Normals -----------------------------------------------------------------------------------------------------
    use_custom_normals: BoolProperty(
        name="Custom Normals",
        description="Shade with the reconstructed (smoothed) normals instead of Blender's own. Costs time at "
                    "every frame change on large meshes; when off, Blender's smooth shading is used",
        default=True,
        options=set(),
        update=_rebuild_after_edit,
    )
    normal_smoothing_iterations: IntProperty(
        name="Normal Smoothing",
        description="How many times the normals are averaged with their neighbours: softer shading, fewer "
                    "visible facets (0: off)",
        default=10, min=0, soft_max=50,
        options=set(),
        update=_rebuild_after_edit,
    )
    sph_normals: BoolProperty(
        name="Particle Normals",
        description="Take normals from the particles' density gradient instead of the mesh: smoother on coarse "
                    "meshes, slower",
        default=False,
        options=set(),
        update=_rebuild_after_edit,
    )

    # Attributes --------------------------------------------------------------------------------------------------
    output_weights: BoolProperty(
        name="Weights Attribute",
        description="Store the feature weights as the point attribute 'weights' (0 in splashes, 1 in calm water), "
                    "e.g. to shade foam with an Attribute node",
        default=False,
        options=set(),
        update=_rebuild_after_edit,
    )
    attribute_names: StringProperty(
        name="Attributes",
        description="Particle attributes to carry onto the surface as point attributes, separated by commas "
                    "(e.g. 'density, temperature'). Velocity is always carried, for motion blur. Names Blender "
                    "gives a meaning of its own get a prefix: 'id' becomes 'particle_id'. Whole-number attributes (ids, "
                    "labels) come from the nearest particle instead of an average",
        default="",
        options=set(),
        update=_rebuild_after_edit,
    )

    # Performance -------------------------------------------------------------------------------------------------
    threads: IntProperty(
        name="Threads",
        description="CPU threads the reconstruction uses (0: all)",
        default=0, min=0, soft_max=64,
        options=set(),
        update=_rebuild_after_edit,
    )
    memory_budget_mb: IntProperty(
        name="Memory Limit (MB)",
        description="Refuse a frame that would need more memory than this, instead of exhausting the machine "
                    "(e.g. after typing a much too small cube size). 0: a share of the installed memory",
        default=0, min=0, soft_max=65536,
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
