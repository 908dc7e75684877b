"""A fluid domain's surface baked and moved: Bake Frame Range bakes a domain source (what only Blender knows, the
obstacles and the domain's matrix at each frame, evaluated on the main thread; the bake's thread reads the cache files
and reconstructs), its baked frames carry the domain in their records (a moved obstacle makes them stale: rebuilt,
not played), and a domain moved or turned after Mantaflow's bake carries its surface along, as Blender's own fluid
mesh follows the domain object (checked in Blender 3.4: the evaluated domain mesh keeps its local coordinates when
the baked domain is moved and turned).

Runs on the pool baked by tests/mantaflow/bake.sh (baked here when missing), its domain rebuilt in a new scene on a
copy of the cache (every Blender: the PyPI bpy modules cannot load Mantaflow caches).
"""
import math
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
bake, update = _support.addon_modules(addon, "blender.bake", "blender.update")

_temporary = tempfile.TemporaryDirectory(prefix="meniscus_fluid_domain_bake_")
COPY = pathlib.Path(_temporary.name) / "pool"
shutil.copytree(BAKE, COPY)
MESHES = pathlib.Path(_temporary.name) / "meshes"
scene, domain = _support.rebuilt_pool_domain(COPY, SCENE["frames"], SCENE["resolution_max"])
obstacle = bpy.data.objects["Obstacle"]
bpy.context.view_layer.objects.active = domain
check(bpy.ops.meniscus.add_fluid_domain_surface() == {"FINISHED"}, "Surface From Fluid Domain refused the pool")
surface = bpy.context.view_layer.objects.active
settings = surface.meniscus
settings.smoothing_iterations = 0
settings.cube_size = settings.render_cube_size = 1.5
settings.cache_pattern = str(MESHES / "pool_####.npz")


def world_vertices(obj):
    local = np.array([v.co for v in obj.data.vertices], dtype=np.float64)
    matrix = np.array(obj.matrix_world, dtype=np.float64)
    return local @ matrix[:3, :3].T + matrix[:3, 3]


def enclosed_volume(obj):
    mesh = obj.data
    mesh.calc_loop_triangles()
    corners = np.zeros(len(mesh.loop_triangles) * 3, dtype=np.int64)
    mesh.loop_triangles.foreach_get("vertices", corners)
    v, t = world_vertices(obj), corners.reshape(-1, 3)
    return float(np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6.0)


def test_bake_frame_range_bakes_a_fluid_domain():
    scene.frame_set(10)
    live = len(surface.data.vertices)
    check(live > 1000 and not settings.status_is_error, settings.status)
    # Keyed obstacle: each frame's task must carry the obstacle where it was at that frame (main-thread evaluation).
    obstacle.location = (0.6, -0.5, 0.25)
    obstacle.keyframe_insert("location", frame=1)
    obstacle.location = (-0.6, 0.5, 0.25)
    obstacle.keyframe_insert("location", frame=SCENE["frames"])
    scene.frame_set(10)
    at = {}
    for frame in (8, 12):
        scene.frame_set(frame)
        at[frame] = np.array(obstacle.matrix_world.translation)
    scene.frame_set(10)
    job, stored = bake.prepare_bake(surface, 8, 12, scene)
    check(scene.frame_current == 10, f"the bake left the scene at frame {scene.frame_current}")
    for task in job.tasks:
        if task.frame in at:
            centre = np.array(task.arguments["fluid_domain"]["obstacles"][0]).reshape(-1, 3).mean(axis=0)
            check(np.allclose(centre, at[task.frame], atol=1e-4), f"frame {task.frame}: obstacle {centre}, was at "
                  f"{at[task.frame]}")
    job.start()  # the bake's own thread, as the operator runs it: it touches no Blender data
    check(job.wait(300), "the bake did not finish")
    summary = bake.finish_bake(surface, job, stored, scene)
    check(job.completed == 5 and not job.failures and summary.startswith("Baked 5 of 5"), summary)
    names = sorted(path.name for path in MESHES.iterdir())
    check(names == sorted([f"pool_{f:04d}.npz" for f in range(8, 13)] + [f"pool_{f:04d}.npz.meniscus" for f in
                                                                           range(8, 13)]), names)
    check(settings.use_cache, "the surface does not play its bake")
    scene.frame_set(11)
    scene.frame_set(10)
    check("pool_0010.npz (cache)" in settings.status and not settings.status_is_error, settings.status)
    check(len(surface.data.vertices) > 1000, len(surface.data.vertices))


def test_a_moved_obstacle_makes_the_baked_frames_stale():
    scene.frame_set(10)
    check("(cache)" in settings.status, settings.status)
    action = obstacle.animation_data.action
    obstacle.animation_data_clear()
    bpy.data.actions.remove(action)
    obstacle.location = (0.5, 0.3, 0.25)
    bpy.context.view_layer.update()  # the obstacle's depsgraph update: the surface checks its baked frame again
    status = settings.status
    check("Stale baked frame pool_0010.npz" in status and "fluid domain" in status and "rebuilt from the fluid cache"
          in status, status)
    check(len(surface.data.vertices) > 1000, len(surface.data.vertices))


def test_a_cancelled_rebake_names_the_frames_of_the_earlier_domain():
    job, stored = bake.prepare_bake(surface, 8, 12, scene)
    job.step()
    job.step()  # frames 8 and 9 baked with the obstacle where it is now
    job.cancel()
    job.step()
    summary = bake.finish_bake(surface, job, stored, scene)
    check(summary.startswith("Baked 2 of 5") and "(cancelled)" in summary and "3 cached frames" in summary and
          "fluid domain" in summary, summary)
    scene.frame_set(9)
    check("pool_0009.npz (cache)" in settings.status, settings.status)
    scene.frame_set(10)
    check("Stale baked frame pool_0010.npz" in settings.status, settings.status)


def test_a_frame_missing_from_the_bake_is_rebuilt_from_the_fluid_cache():
    (MESHES / "pool_0011.npz").unlink()
    scene.frame_set(11)
    check("pp_0011.uni" in settings.status and not settings.status_is_error, settings.status)
    check(len(surface.data.vertices) > 1000, len(surface.data.vertices))


def test_hold_last_good_frame_holds_no_stale_baked_frame():
    (COPY / "cache" / "data" / "pp_0011.uni").rename(COPY / "pp_0011.uni")  # now frame 11 cannot be built at all
    settings.render_failure = "HOLD"
    try:
        scene.frame_set(11)
        with update.exporting(surface) as record:  # built as a final render builds it, failures under the policy
            update.update_surface(surface, scene, force=True)
    finally:
        (COPY / "pp_0011.uni").rename(COPY / "cache" / "data" / "pp_0011.uni")
    # Frame 10 was baked before the obstacle moved, 9 after (the cancelled re-bake): 9 is the water as it is now.
    check(list(record.failed) == [11] and record.failed[11][1] == "pool_0009.npz" and "Missing" in
          record.failed[11][0], record.failed)


def test_a_domain_moved_after_its_bake_carries_its_surface():
    settings.use_cache = False
    scene.frame_set(10)
    check(not settings.status_is_error, settings.status)
    before, volume = world_vertices(surface), enclosed_volume(surface)
    then = np.array(domain.matrix_world, dtype=np.float64)
    domain.location.x += 1.0
    domain.rotation_euler.z = math.radians(30)
    bpy.context.view_layer.update()  # the domain's depsgraph update rebuilds its surface
    update.update_surface(surface, scene)
    check(not settings.status_is_error, settings.status)
    move = np.array(domain.matrix_world, dtype=np.float64) @ np.linalg.inv(then)
    after = world_vertices(surface)
    expected = before.mean(axis=0) @ move[:3, :3].T + move[:3, 3]
    check(np.allclose(after.mean(axis=0), expected, atol=0.01),
          f"the surface's centre is at {after.mean(axis=0)}, the moved domain's liquid at {expected} (before "
          f"{before.mean(axis=0)})")
    # The same water, turned: the reconstruction grid stays aligned with the world, so the mesh differs in detail
    # (its vertex count by some 10 %), not in volume or extent.
    check(abs(enclosed_volume(surface) / volume - 1.0) < 0.01, (enclosed_volume(surface), volume))
    back = np.linalg.solve(move[:3, :3], (after - move[:3, 3]).T).T  # where the domain was
    check(np.allclose(back.min(axis=0), before.min(axis=0), atol=0.03) and
          np.allclose(back.max(axis=0), before.max(axis=0), atol=0.03),
          f"moved back, the surface spans {back.min(axis=0)}-{back.max(axis=0)}, before the move "
          f"{before.min(axis=0)}-{before.max(axis=0)}")


if not _support.AS_MODULE:  # only Blender 3.4 loads Mantaflow's own mesh from the cache (the bpy modules cannot)
    def test_the_surface_follows_a_moved_domain_as_mantaflows_own_mesh_does():
        copy = pathlib.Path(_temporary.name) / "pool_blend"
        shutil.copytree(BAKE, copy)
        bpy.ops.wm.open_mainfile(filepath=str(copy / "scene.blend"))
        baked_scene, baked_domain = bpy.context.scene, bpy.data.objects["Liquid Domain"]
        bpy.context.view_layer.objects.active = baked_domain
        check(bpy.ops.meniscus.add_fluid_domain_surface() == {"FINISHED"}, "Surface From Fluid Domain refused")
        ours = bpy.context.view_layer.objects.active

        def centres():
            evaluated = baked_domain.evaluated_get(bpy.context.evaluated_depsgraph_get())
            mesh = evaluated.to_mesh()
            local = np.array([v.co for v in mesh.vertices], dtype=np.float64)
            evaluated.to_mesh_clear()
            matrix = np.array(evaluated.matrix_world, dtype=np.float64)
            theirs = (local @ matrix[:3, :3].T + matrix[:3, 3]).mean(axis=0)
            check(len(local) > 1000, f"Mantaflow's mesh has {len(local)} vertices (the box?)")
            return world_vertices(ours).mean(axis=0), theirs, enclosed_volume(ours)

        baked_scene.frame_set(12)
        ours_before, theirs_before, volume = centres()
        then = np.array(baked_domain.matrix_world, dtype=np.float64)
        baked_domain.location.x += 1.0
        baked_domain.rotation_euler.z = math.radians(30)
        baked_scene.frame_set(13)
        baked_scene.frame_set(12)
        ours_after, theirs_after, moved_volume = centres()
        move = np.array(baked_domain.matrix_world, dtype=np.float64) @ np.linalg.inv(then)
        follow = lambda point: move[:3, :3] @ point + move[:3, 3]  # noqa: E731
        check(np.allclose(theirs_after, follow(theirs_before), atol=0.01) and np.linalg.norm(theirs_after -
              theirs_before) > 0.5, f"Mantaflow's mesh {theirs_before} -> {theirs_after}")
        check(np.allclose(ours_after, follow(ours_before), atol=0.01), f"ours {ours_before} -> {ours_after}, "
              f"Mantaflow's followed the domain to {theirs_after}")
        check(abs(moved_volume / volume - 1.0) < 0.01, (moved_volume, volume))


_support.run(globals(), cleanup=addon.unregister)
