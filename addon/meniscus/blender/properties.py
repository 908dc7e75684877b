"""Per-object settings of a Meniscus surface: `Object.meniscus`.

Every object that carries `meniscus.is_surface = True` owns one Mesh that the frame handler rebuilds from the
particle file of the current frame. The pipeline's parameters are made from the core's parameter schema (one
property per parameter, same name, label, tooltip, range and default as the API and the command line; a parameter
with an automatic value gets a `<name>_auto` switch beside it); the rest are the add-on's own: where particles come
from, the cache, the viewport cube size, custom normals, which attributes to carry.
"""
import os
import sys

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty, StringProperty

from .. import cache, parameters, sequence
from . import paths, render_policy, update
# Re-exported: callers read the constants and these functions as properties.<name>.
from .arguments import (DRIVEN_BY_ADDON, RENDER_CUBE_SIZE, argument_problems, in_panel_terms,  # noqa: F401
                        label_of, pipeline_arguments)

# The layout of the settings, stored in each surface; files saved before the schema (0) are converted on load.
SETTINGS_VERSION = 3


def _rebuild_after_edit(settings, context):
    # Editing a parameter in the UI should show its effect at once, not at the next frame change.
    if not settings.is_surface:  # the add operator fills many fields before it turns the object into a surface
        return
    update.forget_frames(settings.id_data)  # frames kept for playback were built with the old values
    scene = getattr(context, "scene", None) or bpy.context.scene
    if scene is not None:
        update.update_surface(settings.id_data, scene)


def _play_from_cache_changed(settings, context):
    # Ticked with nothing baked, the fluid would vanish: the switch goes back off and the status says why.
    if settings.use_cache and settings.is_surface and not update.has_cache_frames(settings.id_data):
        settings.use_cache = False
        settings.status = "Nothing baked yet in " + update.cache_pattern_string(settings.id_data) + \
                          ": Bake Frame Range first, then Play From Cache"
        settings.status_is_error = True
        return
    _rebuild_after_edit(settings, context)


_OUT_OF_RANGE_ITEMS = [
    (sequence.HOLD, "Hold", "Show the first frame before the range and the last frame after it"),
    (sequence.LOOP, "Loop", "Repeat the range"),
    (sequence.BLANK, "Blank", "Show nothing outside the range"),
]


def _can_be_source(settings, obj):
    # A surface fed by its own vertices would rebuild from what it just built; other surfaces are allowed.
    # Particle systems live on mesh objects, so MESH covers them too.
    return obj != settings.id_data and obj.type in {"MESH", "POINTCLOUD"}


def _rebuilding(kind, **keywords):
    """A setting that is not animatable and rebuilds the surface when edited."""
    return kind(options=set(), update=_rebuild_after_edit, **keywords)


def _can_be_container(settings, obj):
    # The surface itself would be cut by its own bounds, which follow the cut.
    return obj != settings.id_data


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
        options=paths.BLEND_RELATIVE_OPTIONS,  # '//' paths (see paths)
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

    # Container (the schema's boxes come from this object) ----------------------------------------------------------
    container_object: _rebuilding(
        PointerProperty, type=bpy.types.Object, poll=_can_be_container, name="Container",
        description="Object whose bounds, as they are at each frame (animation included), are the container: the "
                    "surface is cut at its walls and closed there by flat faces (or left open, see Closed At Walls)")
    use_container_particle_box: _rebuilding(
        BoolProperty, default=False, name="Drop Particles Outside",
        description="Also leave out the particles outside the container's bounds before the reconstruction")

    # Cache -------------------------------------------------------------------------------------------------------
    use_cache: BoolProperty(
        name="Play From Cache",
        description="Load the baked meshes instead of reconstructing: scrubbing and rendering only read files "
                    "(frames the cache lacks are rebuilt from the particle files). Needs a bake first",
        default=False,
        options=set(),
        update=_play_from_cache_changed,
    )
    cache_pattern: StringProperty(
        name="Cache Files",
        description="Mesh files of the cache, one per frame: a file of it or a pattern with #### or {} for the frame "
                    "number (.npz baked here, or .ply written by the meniscus command line). Empty: a folder "
                    "'meniscus_cache' next to the .blend",
        subtype="FILE_PATH",
        options=paths.BLEND_RELATIVE_OPTIONS,  # '//' paths (see paths)
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

    # Add-on settings of the pipeline (the pipeline's own parameters are added from the schema below) ------------
    cube_size: FloatProperty(
        name="Viewport Cube Size",
        description="Cube size in the viewport, in particle radii: larger is coarser and faster, for scrubbing (renders "
                    "and bakes use Render Cube Size)",
        default=1.0, min=0.01, soft_min=0.2, soft_max=3.0, precision=2,
        options=set(),
        update=_rebuild_after_edit,
    )
    use_custom_normals: BoolProperty(
        name="Custom Normals",
        description="Shade with the reconstructed (smoothed) normals instead of Blender's own. Costs time at "
                    "every frame change on large meshes; when off, Blender's smooth shading is used",
        default=True,
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
    settings_version: IntProperty(
        name="Settings Version",
        description="Layout of these settings when they were last saved (older files are converted on load)",
        default=0,
        options={"HIDDEN"},
    )

    use_native_cache: BoolProperty(
        name="Plays Alembic",
        description="The surface plays the Alembic file it was exported to (Mesh Sequence Cache modifier), which "
                    "Blender reads without Meniscus; Meniscus does not rebuild it meanwhile",
        default=False,
        options=set(),
    )
    render_failure: EnumProperty(
        name="If a Frame Fails",
        description="What a final render does with a frame whose surface cannot be built (a missing or broken file, "
                    "memory). The viewport always shows such a frame empty, with the reason in the status",
        items=render_policy.ITEMS,
        default=render_policy.STOP,
        options=set(),
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


# Pipeline parameters as properties ------------------------------------------------------------------------------

def _tooltip(parameter):
    unit = f" (in {parameter.unit})" if parameter.unit else ""
    return f"{parameter.help}{unit}"


def _ui_minimum(parameter, precision):
    # Blender's minimum is inclusive: an open bound starts one displayed step above it, so the UI offers no value
    # that the core refuses.
    return parameter.minimum + (10.0 ** -precision if parameter.minimum_open else 0.0)


def _hard_minimum(parameter, precision):
    # An open bound (radius > 0) is not enforced by Blender: it would turn a typed 0 into 0.0001 without a word (a
    # blob per particle, seconds a frame). The value is kept and refused, with the panel's label, when it is used.
    return -sys.float_info.max if parameter.minimum_open else _ui_minimum(parameter, precision)


def parameter_property(parameter, default=None, name=None, description=None):
    """The bpy property of a schema parameter (default: the schema's, or its suggested value where that is
    automatic or required)."""
    value = parameter.suggested if default is None else default
    common = dict(name=name or parameter.label, description=description or _tooltip(parameter), options=set(),
                  update=_rebuild_after_edit)
    if parameter.type == "flag":
        return BoolProperty(default=bool(value), **common)
    if parameter.type == "count":
        return IntProperty(default=int(value), min=int(parameter.minimum), max=int(min(parameter.maximum, 2 ** 31 - 1)),
                           soft_min=int(parameter.soft_minimum), soft_max=int(parameter.soft_maximum), **common)
    precision = 4 if parameter.unit == "scene units" else 2
    extra = {}
    if parameter.unit == "scene units":
        extra = dict(subtype="DISTANCE", unit="LENGTH", step=0.1)
    elif parameter.minimum >= 0.0 and parameter.maximum <= 1.0:
        extra = dict(subtype="FACTOR")
    maximum = parameter.maximum if parameter.maximum < sys.float_info.max else sys.float_info.max
    return FloatProperty(default=float(value), min=_hard_minimum(parameter, precision), max=maximum,
                         soft_min=max(parameter.soft_minimum, _ui_minimum(parameter, precision)),
                         soft_max=parameter.soft_maximum, precision=precision, **common, **extra)


def _add_pipeline_properties(cls):
    """One property per schema parameter (and a <name>_auto switch where it has an automatic value)."""
    for parameter in parameters.PARAMETERS:
        if parameter.name in DRIVEN_BY_ADDON or parameter.type == "vector3":
            continue
        cls.__annotations__[parameter.name] = parameter_property(parameter)
        if parameter.automatic is not None:
            cls.__annotations__[parameter.name + "_auto"] = BoolProperty(
                name="Automatic", default=parameter.default == parameter.automatic, options=set(),
                description=f"Choose {parameter.label} automatically ({parameter.automatic_word}) instead of the value "
                            "beside it", update=_rebuild_after_edit)
    cube = parameters.BY_NAME["cube_size"]
    cls.__annotations__[RENDER_CUBE_SIZE] = parameter_property(
        cube, default=cube.default, name="Render Cube Size",
        description=_tooltip(cube) + ". Used for renders and bakes; the viewport uses Viewport Cube Size")


_add_pipeline_properties(MeniscusSurfaceSettings)


def automatic_meaning(name):
    """What an automatic value means on this machine, for the panel: 'the free ones of 16 cores', '75 % of 31.2 GiB'."""
    if name == "threads":
        limit = os.environ.get("OMP_NUM_THREADS", "").split(",")[0]
        if limit.isdigit():
            return f"{limit} (OMP_NUM_THREADS)"
        # On Linux the core leaves the cores other programs keep busy (native/core/base/machine_load.h).
        cores = os.cpu_count() or 1
        return f"the free ones of {cores} cores" if sys.platform.startswith("linux") else f"all {cores} cores"
    if name == "memory_budget":
        installed = _installed_memory()
        return f"75 % of {installed / 2 ** 30:.1f} GiB" if installed else "75 % of the installed memory"
    return parameters.BY_NAME[name].automatic_word


def _installed_memory():
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):  # Windows has no sysconf
        pass
    try:
        import ctypes

        class _MemoryStatus(ctypes.Structure):
            _fields_ = [("length", ctypes.c_ulong), ("load", ctypes.c_ulong), ("total", ctypes.c_ulonglong),
                        ("available", ctypes.c_ulonglong), ("rest", ctypes.c_ulonglong * 5)]

        status = _MemoryStatus(length=ctypes.sizeof(_MemoryStatus))
        return status.total if ctypes.windll.kernel32.GlobalMemoryStatusEx(ctypes.byref(status)) else 0
    except Exception:
        return 0


# Settings of files saved before the schema (layout 0) -------------------------------------------------------------

def migrate_settings(settings):
    """Converts a surface's settings from an older layout (renamed or re-expressed properties) in place, keeping
    every value the user set; returns True when something was converted. Older files store their values as raw ID
    properties under the old names, which Blender keeps even though no property of that name exists any more."""
    if settings.get("settings_version", 0) >= SETTINGS_VERSION:
        return False
    if "use_feature_weights" in settings:
        settings.smoothing_weights = bool(settings["use_feature_weights"])
    if "use_snap_distance" in settings:
        settings.mesh_cleanup_snap_distance_auto = not settings["use_snap_distance"]
    if "memory_budget_mb" in settings:
        megabytes = int(settings["memory_budget_mb"])
        settings.memory_budget_auto = megabytes == 0
        if megabytes > 0:
            settings.memory_budget = megabytes / 1024.0
    if "threads" in settings and int(settings["threads"]) > 0:
        settings.threads_auto = False
    if settings.get("settings_version", 0) < 3 and "smoothing_reach" not in settings:
        # Before version 3 the reach was off by default: a file that never set it keeps the iterations it was made with.
        settings.smoothing_reach = 0.0
    for old in ("use_feature_weights", "use_snap_distance", "memory_budget_mb"):
        if old in settings:
            del settings[old]
    settings.settings_version = SETTINGS_VERSION
    return True


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
