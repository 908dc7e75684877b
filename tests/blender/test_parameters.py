"""N-panel completeness: every pipeline parameter is a documented property that reaches the core; viewport and
render cube sizes; weights and particle attributes as mesh attributes; the memory budget's refusal in the status.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import sys
import tempfile

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check, mesh_counts  # noqa: E402

addon = _support.enable_addon()
api = addon.api
update, mesh_update, panels = _support.addon_modules(addon, "blender.update", "blender.mesh_update", "blender.panels")

_temporary = tempfile.TemporaryDirectory(prefix="meniscus_params_")
_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()
settings = surface.meniscus
settings.is_surface = False
settings.cube_size, settings.render_cube_size = 2.0, 1.2
settings.smoothing_iterations, settings.normal_smoothing_iterations = 2, 1
settings.is_surface = True
scene.frame_set(30)

properties, render_state = _support.addon_modules(addon, "blender.properties", "blender.render_state")
schema = addon.parameters
ADDON_SETTINGS = ("render_cube_size", "use_custom_normals", "attribute_names", "source_type", "source_object",
                  "use_cache", "cache_pattern", "cache_format")


def test_every_schema_parameter_is_a_property_with_the_schemas_tooltip_and_default():
    rna = type(settings).bl_rna.properties
    for parameter in schema.PARAMETERS:
        if parameter.name in properties.DRIVEN_BY_ADDON or parameter.type == "vector3":  # boxes: from an object
            continue
        check(parameter.name in rna, f"no property for the parameter {parameter.name}")
        prop = rna[parameter.name]
        check(prop.name == parameter.label and prop.description.startswith(parameter.help),
              f"{parameter.name}: {prop.name!r}, {prop.description!r}")
        expected = parameter.suggested if parameter.required or parameter.automatic is not None else parameter.default
        check(abs(float(prop.default) - expected) < 1e-6, f"{parameter.name}: default {prop.default}, schema {expected}")
        if parameter.type != "flag":  # the UI's slider offers no value the core refuses
            unbounded = prop.hard_max > 1e30  # the UI's way of saying "no maximum"
            # An open minimum (radius > 0) is not enforced: a typed 0 is kept and refused by its label (test_user_errors),
            # where Blender would raise it to the smallest step without a word.
            lowest = prop.soft_min if parameter.minimum_open else prop.hard_min
            check(parameter.problem(lowest) is None and (unbounded or parameter.problem(prop.hard_max) is None),
                  f"{parameter.name}: UI range {prop.hard_min}..{prop.hard_max}")
        if parameter.automatic is not None:
            check(parameter.name + "_auto" in rna, f"{parameter.name}: no automatic switch")
    for name in ADDON_SETTINGS:
        check(name in rna and len(rna[name].description) > 25, f"{name}: missing or thin tooltip")
    arguments = update.reconstruction_arguments(settings, for_render=False)
    check(set(arguments) == set(schema.BY_NAME), set(arguments) ^ set(schema.BY_NAME))
    check(arguments["cube_size"] == settings.cube_size, "viewport cube size")
    check(update.reconstruction_arguments(settings, for_render=True)["cube_size"] == settings.render_cube_size,
          "render cube size")
    check(arguments["weights_normalization"] == 0.0 and arguments["threads"] == 0, "automatic values")
    # The sub-panels group them; every one is registered under the main panel.
    for panel in panels.classes[1:]:
        check(getattr(bpy.types, panel.__name__, None) is not None, f"{panel.__name__} not registered")
        check(panel.bl_parent_id == "MENISCUS_PT_main", panel.__name__)
    groups = {panel.group for panel in panels.classes if hasattr(panel, "group")}
    check(set(schema.GROUPS) <= groups, f"groups without a panel: {set(schema.GROUPS) - groups}")


def test_a_value_the_core_refuses_is_reported_with_the_panels_label():
    settings["smoothing_strength"] = 0.0  # below the UI minimum: as a script or an old file could set it
    update.update_surface(surface, scene, force=True)
    status = settings.status
    check(settings.status_is_error and status == "Smoothing Strength must be a number greater than 0 and at most 1, got 0",
          status)
    settings.smoothing_strength = 1.0
    check(not settings.status_is_error, settings.status)


def test_settings_of_older_files_are_converted():
    legacy = _support.add_sample_sequence()
    old = legacy.meniscus
    old.is_surface = False
    for key in list(old.keys()):
        if key == "settings_version":
            del old[key]
    # As a file saved by 0.1 stores them: raw values under the old names.
    old["use_feature_weights"] = 0
    old["use_snap_distance"] = 1
    old["memory_budget_mb"] = 2048
    old["threads"] = 3
    check(properties.migrate_settings(old), "nothing converted")
    check(not old.smoothing_weights and not old.mesh_cleanup_snap_distance_auto, "flags")
    check(not old.memory_budget_auto and abs(old.memory_budget - 2.0) < 1e-9, (old.memory_budget_auto, old.memory_budget))
    check(not old.threads_auto and old.threads == 3, (old.threads_auto, old.threads))
    check("use_feature_weights" not in old.keys() and old.settings_version == properties.SETTINGS_VERSION, old.keys())
    check(old.smoothing_reach == 0.0, "a file from before the reach's default keeps the iterations it was made with")
    check(not properties.migrate_settings(old), "a converted object must not be converted again")
    bpy.data.objects.remove(legacy)


def test_each_parameter_edit_reaches_the_core():
    scene.frame_set(30)
    check(abs(settings.smoothing_reach - schema.BY_NAME["smoothing_reach"].default) < 1e-6, "a new surface gets the reach")
    settings.smoothing_reach = 0.0  # the iterations, whose count, strength and restoration then matter too
    baseline = mesh_update.read_vertices(surface.data).copy()
    changes = [("smoothing_length", 2.4), ("iso_threshold", 0.5), ("smoothing_iterations", 4), ("smoothing_reach", 3.0),
               ("smoothing_strength", 0.5), ("smoothing_weights", False), ("volume_restoration", False),
               ("decimate_barnacles", False), ("mesh_cleanup", True), ("normal_smoothing_iterations", 3),
               ("sph_normals", True)]
    for name, value in changes:
        old = getattr(settings, name)
        setattr(settings, name, value)  # the update callback rebuilds at once
        check(not settings.status_is_error, f"{name}={value}: {settings.status}")
        changed = mesh_update.read_vertices(surface.data)
        if name in ("normal_smoothing_iterations", "sph_normals"):  # normals only: compare shading normals
            pass
        else:
            check(changed.shape != baseline.shape or not np.array_equal(changed, baseline),
                  f"changing {name} did not change the surface")
        setattr(settings, name, old)
    settings.mesh_cleanup = True
    settings.mesh_cleanup_snap_distance_auto = False
    settings.mesh_cleanup_snap_distance = 0.1
    check(not settings.status_is_error, settings.status)
    settings.mesh_cleanup = False
    settings.mesh_cleanup_snap_distance_auto = True
    settings.weights_normalization_auto = False
    settings.weights_normalization = 30.0
    check(not settings.status_is_error and not np.array_equal(mesh_update.read_vertices(surface.data), baseline),
          "a fixed weights normalisation should change the surface")
    settings.weights_normalization_auto = True
    settings.smoothing_reach = schema.BY_NAME["smoothing_reach"].default


def test_quads_and_stray_removal_reach_the_mesh():
    scene.frame_set(30)
    triangles_only = len(surface.data.polygons)
    settings.generate_quads = True
    try:
        check(not settings.status_is_error, settings.status)
        sizes = np.zeros(len(surface.data.polygons), dtype=np.int32)
        surface.data.polygons.foreach_get("loop_total", sizes)
        check(set(np.unique(sizes)) == {3, 4} and (sizes == 4).sum() > 100, f"face sizes {np.bincount(sizes)}")
        # Each quad replaced two triangles.
        check(len(sizes) + (sizes == 4).sum() == triangles_only, (len(sizes), (sizes == 4).sum(), triangles_only))
    finally:
        settings.generate_quads = False
    before = len(surface.data.vertices)
    settings.stray_min_particles = 50  # the splash droplets of the sample frame go, the pools stay
    try:
        check(not settings.status_is_error, settings.status)
        check(0 < len(surface.data.vertices) < before, (len(surface.data.vertices), before))
    finally:
        settings.stray_min_particles = 0


def test_weights_and_particle_attributes_become_mesh_attributes():
    settings.output_weights = True
    settings.attribute_names = "id, foam"  # 'id' is in the sample files, 'foam' is not
    weights = mesh_update.read_point_values(surface.data, "weights")
    check(weights is not None and len(weights) == len(surface.data.vertices), "no 'weights' point attribute")
    check(surface.data.attributes["weights"].data_type == "FLOAT", surface.data.attributes["weights"].data_type)
    check(weights.min() >= -1e-5 and weights.max() <= 1.0 + 1e-5 and np.ptp(weights) > 0.1, (weights.min(), weights.max()))
    # Particle ids are whole numbers: each vertex carries its nearest particle's id (an average of ids would mean
    # nothing), as an INT attribute; 'id' has a meaning of its own in Blender, so it is stored as 'particle_id' in
    # every version, and the status says so.
    ids = mesh_update.read_point_values(surface.data, "particle_id")
    check(ids is not None and surface.data.attributes["particle_id"].data_type == "INT", "'id' not stored as INT particle_id")
    particle_ids = api.read_particles(_support.SAMPLE_PATTERN.replace("####", "0030")).attributes["id"]
    check(np.isin(ids, particle_ids).all(), "vertex ids must be ids of particles, not blends of them")
    check(len(np.unique(ids)) > 100, f"only {len(np.unique(ids))} distinct ids on the surface")
    check("'id' stored as 'particle_id'" in settings.status, settings.status)
    check("foam" in settings.status and not settings.status_is_error, settings.status)
    check(mesh_update.read_point_vectors(surface.data, "velocity") is not None, "velocity must stay")
    settings.output_weights = False
    settings.attribute_names = ""
    check("weights" not in surface.data.attributes and "particle_id" not in surface.data.attributes,
          "attributes that are no longer produced must not linger")


def test_memory_budget_refusal_shows_in_the_status():
    meshes = len(bpy.data.meshes)
    settings.memory_budget_auto = False
    settings.memory_budget = 1 / 1024  # 1 MiB
    settings.cube_size = 0.1  # the mistake the budget is for: ~50x more cells than the viewport needs
    status = settings.status
    check(settings.status_is_error and "memory budget" in status and "GiB" in status, status)
    check(mesh_counts(surface) == (0, 0), "a refused frame shows an empty mesh")
    print(f"     status: {status}")
    settings.cube_size = 2.0
    settings.memory_budget_auto = True
    check(not settings.status_is_error and mesh_counts(surface)[0] > 0, settings.status)
    check(len(bpy.data.meshes) == meshes, "no meshes may be left behind")


def test_renders_use_the_render_cube_size():
    render_arguments = update.reconstruction_arguments(settings, for_render=True)
    particles = api.read_particles(_support.SAMPLE_DIR / "double_dam_break_0030.vtk")
    expected = len(api.reconstruct(particles.positions, attributes={"velocity": particles.attributes["velocity"]},
                                   **render_arguments).triangles)
    scene.frame_set(30)
    viewport = mesh_counts(surface)[1]
    check(viewport != expected, "test needs different viewport and render triangle counts")
    seen = []

    def record(_scene, *_args):
        seen.append((len(surface.data.polygons), render_state.is_rendering()))

    _support.make_small_render(scene)
    bpy.app.handlers.render_post.append(record)
    try:
        bpy.ops.render.render()  # a still: no frame change, so render_pre must switch to the render settings
        scene.render.filepath = os.path.join(_temporary.name, "f_####")
        scene.frame_start = scene.frame_end = 31
        bpy.ops.render.render(animation=True)  # an animation: the frame change happens inside the render
    finally:
        bpy.app.handlers.render_post.remove(record)
    check(seen[0] == (expected, True), f"still render used {seen[0]}, want ({expected}, True)")
    check(seen[1][1] and seen[1][0] > viewport, f"animation render used {seen[1]}")
    check(not render_state.is_rendering(), "the render flag must be cleared after the render")
    scene.frame_set(32)
    scene.frame_set(30)
    check(mesh_counts(surface)[1] == viewport, "after rendering, the viewport settings apply again")


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
