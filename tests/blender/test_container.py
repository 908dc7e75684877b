"""The container object: a cube chosen in the Container panel cuts the surface at its bounds, closed by flat faces
on its walls, and the cut follows the cube's animation; the particle box switch drops the particles outside.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import sys
import tempfile

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
api = addon.api
update, container, bake = _support.addon_modules(addon, "blender.update", "blender.container", "blender.bake")
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_container_")

_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()
settings = surface.meniscus
settings.is_surface = False
settings.cube_size = 1.0
settings.smoothing_iterations = 5
settings.is_surface = True

particles = api.read_particles(_support.SAMPLE_DIR / "double_dam_break_0030.vtk").positions
low, high = particles.min(axis=0), particles.max(axis=0)
# A box inside the particles' reach on every side but the top: the fluid is cut by its four sides and its floor.
box_low = low + 0.2 * (high - low)
box_high = np.array([*(high - 0.2 * (high - low))[:2], high[2] + 1.0])

bpy.ops.mesh.primitive_cube_add(size=1.0)
cube = bpy.context.active_object
cube.name = "Tank"
cube.location = tuple((box_low + box_high) / 2)
cube.scale = tuple(box_high - box_low)
bpy.context.view_layer.objects.active = surface
settings.container_object = cube


def world_vertices(obj):
    coords = np.empty(3 * len(obj.data.vertices), dtype=np.float32)
    obj.data.vertices.foreach_get("co", coords)
    coords = coords.reshape(-1, 3)
    matrix = np.array(obj.matrix_world)
    return coords @ matrix[:3, :3].T + matrix[:3, 3]


def cube_bounds():
    return container.world_bounds(cube.bound_box, cube.matrix_world)


def vertices_inside(lower, upper, tolerance=1e-5):
    vertices = world_vertices(surface)
    return len(vertices) > 0 and bool(np.all((vertices >= np.array(lower) - tolerance) & (vertices <= np.array(upper) + tolerance)))


def test_the_surface_lies_inside_the_container_cube():
    scene.frame_set(30)
    lower, upper = cube_bounds()
    np.testing.assert_allclose(lower, box_low, atol=1e-5)
    check(vertices_inside(lower, upper), f"vertices outside the cube's bounds {lower}..{upper}; status: {settings.status}")
    # The floor is capped: many vertices lie on its plane.
    on_floor = np.abs(world_vertices(surface)[:, 2] - lower[2]) < 1e-5
    check(on_floor.sum() > 50, f"{on_floor.sum()} vertices on the floor")
    arguments = update.reconstruction_arguments(settings, for_render=False)
    check(arguments["mesh_aabb_min"] == lower and arguments["particle_aabb_min"] is None, arguments)


def test_the_cut_follows_the_cubes_animation():
    start = cube.location.copy()
    cube.keyframe_insert("location", frame=30)
    cube.location.x += 0.1 * (high[0] - low[0])
    cube.keyframe_insert("location", frame=31)
    try:
        scene.frame_set(31)
        lower, upper = cube_bounds()
        check(abs(lower[0] - (box_low[0] + 0.1 * (high[0] - low[0]))) < 1e-5, f"cube at frame 31: {lower}")
        check(vertices_inside(lower, upper), f"vertices outside the moved cube's bounds; status: {settings.status}")
        check(update.reconstruction_arguments(settings, for_render=False)["mesh_aabb_min"] == lower, "arguments")
    finally:
        cube.animation_data_clear()
        cube.location = start
        scene.frame_set(30)


def test_moving_the_cube_rebuilds_the_surface():
    start = cube.location.copy()
    try:
        scene.frame_set(30)
        cube.location.x += 0.1 * (high[0] - low[0])
        bpy.context.view_layer.update()  # the depsgraph update handler sees the container move
        lower, upper = cube_bounds()
        check(vertices_inside(lower, upper), f"after moving the cube, vertices outside its bounds; status: {settings.status}")
        check(world_vertices(surface)[:, 0].max() > box_high[0] + 1e-3, "the surface still ends at the cube's old wall")
    finally:
        cube.location = start
        bpy.context.view_layer.update()


def test_a_bake_follows_the_cubes_animation():
    start = cube.location.copy()
    shift = 0.1 * (high[0] - low[0])
    cube.keyframe_insert("location", frame=30)
    cube.location.x += shift
    cube.keyframe_insert("location", frame=31)
    scene.frame_set(30)
    settings.cache_pattern = os.path.join(_temporary.name, "cache", "tank_####.npz")
    try:
        job = bake.bake_surface(surface, scene, 30, 31)
        check(job.completed == 2 and not job.failures, f"{job.completed} frames, failures {job.failures}")
        check(scene.frame_current == 30, "the bake must leave the scene at its frame")
        for frame, moved in ((30, 0.0), (31, shift)):
            lower = np.array(box_low) + [moved, 0, 0]
            upper = np.array(box_high) + [moved, 0, 0]
            vertices = addon.cache.load_mesh(settings.cache_pattern.replace("####", f"{frame:04d}")).vertices
            check(len(vertices) > 0 and np.all((vertices >= lower - 1e-5) & (vertices <= upper + 1e-5)),
                  f"frame {frame}: baked vertices outside the cube's bounds at that frame")
            check(np.abs(vertices[:, 0] - upper[0]).min() < 1e-5, f"frame {frame}: no vertex on the moved wall")
    finally:
        settings.use_cache = False
        settings.cache_pattern = ""
        cube.animation_data_clear()
        cube.location = start
        scene.frame_set(30)


def test_drop_particles_outside_and_no_container():
    settings.use_container_particle_box = True
    arguments = update.reconstruction_arguments(settings, for_render=False)
    check(arguments["particle_aabb_min"] == arguments["mesh_aabb_min"] is not None, arguments)
    settings.use_container_particle_box = False
    settings.container_object = None
    arguments = update.reconstruction_arguments(settings, for_render=False)
    check(all(arguments[name] is None for name in ("mesh_aabb_min", "mesh_aabb_max", "particle_aabb_min")), arguments)
    scene.frame_set(31)
    scene.frame_set(30)
    check(not vertices_inside(box_low, box_high), "without a container the surface is not cut")


def test_opening_a_saved_file_builds_inside_the_container():
    # Blender 4.2+ saves no world matrices: the load handler must not build before the scene is evaluated, or the
    # container is the unit cube at the origin until the frame changes.
    settings.container_object = cube
    scene.frame_set(30)
    built = _support.mesh_counts(surface)
    blend = os.path.join(_temporary.name, "tank.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    surface_name = surface.name
    bpy.ops.wm.open_mainfile(filepath=blend)
    loaded = bpy.data.objects[surface_name]
    lower, upper = container.world_bounds(loaded.meniscus.container_object.bound_box,
                                          loaded.meniscus.container_object.matrix_world)
    np.testing.assert_allclose(lower, box_low, atol=1e-5)
    check(_support.mesh_counts(loaded) == built, f"after opening: {_support.mesh_counts(loaded)}, saved with {built}; "
                                                 f"{loaded.meniscus.status}")


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
