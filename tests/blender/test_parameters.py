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
handlers, mesh_update, panels = _support.addon_modules(addon, "blender.handlers", "blender.mesh_update", "blender.panels")

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

# Every keyword of api.reconstruct a user can set, and the property that drives it.
PIPELINE_PROPERTIES = {
    "particle_radius": "particle_radius", "smoothing_length": "smoothing_length", "cube_size": "cube_size",
    "iso_threshold": "iso_threshold", "smoothing_iterations": "smoothing_iterations",
    "smoothing_beta": "smoothing_strength", "smoothing_weights": "use_feature_weights",
    "weights_normalization": "weights_normalization", "volume_restoration": "volume_restoration",
    "decimate_barnacles": "decimate_barnacles", "mesh_cleanup": "mesh_cleanup",
    "mesh_cleanup_snap_distance": "mesh_cleanup_snap_distance", "normal_smoothing_iterations":
    "normal_smoothing_iterations", "sph_normals": "sph_normals", "output_weights": "output_weights",
    "threads": "threads", "memory_budget": "memory_budget_mb", "normals": "use_custom_normals",
}
EXTRA_PROPERTIES = ("render_cube_size", "weights_normalization_auto", "use_snap_distance", "attribute_names",
                    "source_type", "source_object", "use_cache", "cache_pattern", "cache_format")


def test_every_parameter_is_a_property_with_a_tooltip():
    rna = type(settings).bl_rna.properties
    for name in list(PIPELINE_PROPERTIES.values()) + list(EXTRA_PROPERTIES):
        check(name in rna, f"no property {name}")
        description = rna[name].description
        check(len(description) > 25 and description[0].isupper(), f"{name}: tooltip too thin: {description!r}")
    arguments = handlers.reconstruction_arguments(settings, for_render=False)
    check(set(arguments) == set(PIPELINE_PROPERTIES), set(arguments) ^ set(PIPELINE_PROPERTIES))
    check(arguments["cube_size"] == settings.cube_size, "viewport cube size")
    check(handlers.reconstruction_arguments(settings, for_render=True)["cube_size"] == settings.render_cube_size,
          "render cube size")
    # The sub-panels group them; every one is registered under the main panel.
    for panel in panels.classes[1:]:
        check(getattr(bpy.types, panel.__name__, None) is not None, f"{panel.__name__} not registered")
        check(panel.bl_parent_id == "MENISCUS_PT_main", panel.__name__)
    check(len(panels.classes) >= 7, "expected sub-panels for source, cache, surface, smoothing, mesh, normals, ...")


def test_each_parameter_edit_reaches_the_core():
    scene.frame_set(30)
    baseline = mesh_update.read_vertices(surface.data).copy()
    changes = [("smoothing_length", 2.4), ("iso_threshold", 0.5), ("smoothing_iterations", 4),
               ("smoothing_strength", 0.5), ("use_feature_weights", False), ("volume_restoration", False),
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
    settings.use_snap_distance = True
    settings.mesh_cleanup_snap_distance = 0.1
    check(not settings.status_is_error, settings.status)
    settings.mesh_cleanup = False
    settings.use_snap_distance = False
    settings.weights_normalization_auto = False
    settings.weights_normalization = 30.0
    check(not settings.status_is_error and not np.array_equal(mesh_update.read_vertices(surface.data), baseline),
          "a fixed weights normalisation should change the surface")
    settings.weights_normalization_auto = True


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
    settings.memory_budget_mb = 1
    settings.cube_size = 0.1  # the mistake the budget is for: ~50x more cells than the viewport needs
    status = settings.status
    check(settings.status_is_error and "memory budget" in status and "GiB" in status, status)
    check(mesh_counts(surface) == (0, 0), "a refused frame shows an empty mesh")
    print(f"     status: {status}")
    settings.cube_size = 2.0
    settings.memory_budget_mb = 0
    check(not settings.status_is_error and mesh_counts(surface)[0] > 0, settings.status)
    check(len(bpy.data.meshes) == meshes, "no meshes may be left behind")


def test_renders_use_the_render_cube_size():
    render_arguments = handlers.reconstruction_arguments(settings, for_render=True)
    particles = api.read_particles(_support.SAMPLE_DIR / "double_dam_break_0030.vtk")
    expected = len(api.reconstruct(particles.positions, attributes={"velocity": particles.attributes["velocity"]},
                                   **render_arguments).triangles)
    scene.frame_set(30)
    viewport = mesh_counts(surface)[1]
    check(viewport != expected, "test needs different viewport and render triangle counts")
    seen = []

    def record(_scene, *_args):
        seen.append((len(surface.data.polygons), handlers.is_rendering()))

    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.location = (1.5, -3.5, 2.0)
    camera.rotation_euler = (np.radians(65), 0.0, 0.0)
    scene.camera = camera
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 16, 9, 100
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
    check(not handlers.is_rendering(), "the render flag must be cleared after the render")
    scene.frame_set(32)
    scene.frame_set(30)
    check(mesh_counts(surface)[1] == viewport, "after rendering, the viewport settings apply again")


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
