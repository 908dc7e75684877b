"""A fluid domain's surface is never a stale fill: what the narrow-band fill used besides the particles (the domain's
borders, Narrow Band Width, its obstacles where they were at the cache frame, the cache files) decides whether the
frame shown is current.

- Changing a border, the Narrow Band Width, a static obstacle's transform or the cache folder without a frame change
  rebuilds the surface with the new values (the playback key carries a digest of them).
- Obstacles are placed where they were at the cache frame (the scene frame minus the domain's Frame Offset: where
  Mantaflow had them when it simulated that frame), and Hold Last Good Frame places them at the held frame.

Runs on the pool baked by tests/mantaflow/bake.sh (baked here when missing), its domain rebuilt in a new scene on a
copy of the cache (every Blender: the PyPI bpy modules cannot load Mantaflow caches, and a rebuilt domain whose
modifier is off lets its settings change without Blender touching the cache).
"""
import os
import pathlib
import shutil
import sys
import tempfile

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

BAKE, SCENE = _support.mantaflow_bake("pool_UNI")

addon = _support.enable_addon()
fluid_domain, update, render_policy = _support.addon_modules(addon, "blender.fluid_domain", "blender.update",
                                                             "blender.render_policy")

# What reached the core: the add-on's reconstructions go through the library's cache.reconstruct_positions.
calls = []
_reconstruct_positions = update.cache.reconstruct_positions


def _recording(positions, attributes, arguments, wanted=()):
    calls.append(arguments.get("fluid_domain"))
    return _reconstruct_positions(positions, attributes, arguments, wanted)


update.cache.reconstruct_positions = _recording

_temporary = tempfile.TemporaryDirectory(prefix="meniscus_fluid_domain_stale_")
COPY = pathlib.Path(_temporary.name) / "pool"
shutil.copytree(BAKE, COPY)
scene, domain = _support.rebuilt_pool_domain(COPY, SCENE["frames"], SCENE["resolution_max"])
domain_settings = fluid_domain.domain_settings(domain)
obstacle = bpy.data.objects["Obstacle"]
bpy.context.view_layer.objects.active = domain
check(bpy.ops.meniscus.add_fluid_domain_surface() == {"FINISHED"}, "Surface From Fluid Domain refused the pool")
surface = bpy.context.view_layer.objects.active
settings = surface.meniscus
settings.smoothing_iterations = 0  # what reaches the core matters here, not the smoothing
settings.cube_size = settings.render_cube_size = 1.5


def obstacle_centre(domain_dict):
    return np.array(domain_dict["obstacles"][0]).reshape(-1, 3).mean(axis=0)


def rebuilt_after(change):
    """Applies change() at an unchanged frame, then what follows an edit in Blender (the depsgraph update, whose
    handler rebuilds surfaces whose source changed) and one more update of the surface; returns the fluid domain of
    the one rebuild this caused (fails when the surface kept the fill it showed)."""
    scene.frame_set(10)
    check(not settings.status_is_error, settings.status)
    del calls[:]
    change()
    bpy.context.view_layer.update()
    if not (COPY / "cache" / "data" / "pp_0010.uni").is_file():
        # Blender deletes a domain's cache when some settings change (3.4 does for a border): then the surface
        # says so rather than keep the fill it showed.
        update.update_surface(surface, scene)
        check(settings.status_is_error and "not baked" in settings.status and len(surface.data.vertices) == 0,
              f"the cache was deleted, the surface shows: {settings.status}")
        # What a new bake would bring back, here the same files (same sizes and times): only the change differs.
        shutil.copytree(BAKE / "cache", COPY / "cache", dirs_exist_ok=True)
        del calls[:]
    update.update_surface(surface, scene)
    check(len(calls) == 1, f"{len(calls)} reconstructions after the change: the previous fill stays shown; status "
          f"{settings.status}")
    check(not settings.status_is_error, settings.status)
    return calls[-1]


def test_a_border_change_rebuilds_the_fill():
    domain_dict = rebuilt_after(lambda: setattr(domain_settings, "use_collision_border_top", False))
    check(domain_dict["closed_borders"] == [True] * 5 + [False], domain_dict["closed_borders"])
    domain_dict = rebuilt_after(lambda: setattr(domain_settings, "use_collision_border_top", True))
    check(domain_dict["closed_borders"] == [True] * 6, domain_dict["closed_borders"])


def test_a_narrow_band_width_change_rebuilds_the_fill():
    domain_dict = rebuilt_after(lambda: setattr(domain_settings, "particle_band_width", 5.0))
    check(domain_dict["band_width_cells"] == 5.0, domain_dict["band_width_cells"])
    rebuilt_after(lambda: setattr(domain_settings, "particle_band_width", SCENE["particle_band_width"]))


def test_a_moved_static_obstacle_rebuilds_the_fill():
    def move():
        obstacle.location.x -= 0.2
    domain_dict = rebuilt_after(move)
    check(np.allclose(obstacle_centre(domain_dict), [0.3, 0.3, 0.25], atol=1e-4), obstacle_centre(domain_dict))
    # The depsgraph update of the obstacle alone (what moving it in the viewport sends) rebuilds the surface too.
    del calls[:]
    obstacle.location.x += 0.2
    bpy.context.view_layer.update()
    check(len(calls) == 1 and np.allclose(obstacle_centre(calls[-1]), [0.5, 0.3, 0.25], atol=1e-4),
          f"{len(calls)} rebuilds after the obstacle's depsgraph update")


def test_another_cache_folder_rebuilds_the_fill():
    other = pathlib.Path(_temporary.name) / "pool_other_cache"
    shutil.copytree(COPY / "cache", other, copy_function=shutil.copy)  # the same particles, files of their own
    rebuilt_after(lambda: setattr(domain_settings, "cache_directory", str(other)))
    check((other / "data" / "pp_0010.uni").is_file(), "the cache copy lost its files")
    rebuilt_after(lambda: setattr(domain_settings, "cache_directory", "//cache"))


def key_obstacle(first, last):
    """Keys the obstacle sliding from (0.6, -0.5) at frame `first` to (-0.6, 0.5) at `last` (linear)."""
    obstacle.location = (0.6, -0.5, 0.25)
    obstacle.keyframe_insert("location", frame=first)
    obstacle.location = (-0.6, 0.5, 0.25)
    obstacle.keyframe_insert("location", frame=last)
    for curve in update.fluid_domain._fcurves(obstacle):
        for point in curve.keyframe_points:
            point.interpolation = "LINEAR"


def sliding_centre(frame, first, last):
    t = (frame - first) / (last - first)
    return np.array([0.6 - 1.2 * t, -0.5 + 1.0 * t, 0.25])


def test_obstacles_are_where_they_were_at_the_cache_frame():
    key_obstacle(1, 30)
    domain_settings.cache_frame_offset = 5
    try:
        del calls[:]
        scene.frame_set(15)  # cache frame 10: Mantaflow simulated it with the obstacle where it was at frame 10
        check("pp_0010.uni" in settings.status and not settings.status_is_error, settings.status)
        check(len(calls) == 1, f"{len(calls)} reconstructions")
        centre = obstacle_centre(calls[-1])
        check(np.allclose(centre, sliding_centre(10, 1, 30), atol=1e-4),
              f"obstacle passed at {centre}: at frame 10 it was at {sliding_centre(10, 1, 30)}, now (frame 15) at "
              f"{np.array(obstacle.matrix_world.translation)}")
        # Evaluated from the F-curves as Blender places it: the same matrix as the depsgraph's at the current frame.
        check(np.allclose(np.array(fluid_domain._matrix_at(obstacle, 15)), np.array(obstacle.matrix_world), atol=1e-5),
              (fluid_domain._matrix_at(obstacle, 15), obstacle.matrix_world))
    finally:
        domain_settings.cache_frame_offset = 0


def test_an_obstacle_moved_by_a_constraint_is_refused_at_another_cache_frame():
    constraint = obstacle.constraints.new("LIMIT_LOCATION")
    domain_settings.cache_frame_offset = 5
    try:
        scene.frame_set(15)
        check(settings.status_is_error and "Obstacle 'Obstacle'" in settings.status and "constraints" in
              settings.status and "frame 10" in settings.status, settings.status)
    finally:
        obstacle.constraints.remove(constraint)
        domain_settings.cache_frame_offset = 0


def test_hold_last_good_frame_places_obstacles_at_the_held_frame():
    last = SCENE["frames"]
    settings.render_failure = render_policy.HOLD
    scene.frame_set(last + 1)  # outside the bake: the viewport shows the error
    del calls[:]
    with update.exporting(surface) as record:  # built as a final render builds it, failures under the policy
        update.update_surface(surface, scene, force=True)
    check(list(record.failed) == [last + 1] and record.failed[last + 1][1] == f"pp_{last:04d}.uni", record.failed)
    check(len(calls) == 1, f"{len(calls)} reconstructions")
    centre = obstacle_centre(calls[-1])
    check(np.allclose(centre, sliding_centre(last, 1, 30), atol=1e-4),
          f"held frame {last} got the obstacle at {centre}: it was at {sliding_centre(last, 1, 30)} then, at "
          f"{np.array(obstacle.matrix_world.translation)} now")


_support.run(globals(), cleanup=addon.unregister)
