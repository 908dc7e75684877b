"""Bake and cache: a frame range baked to mesh files, then played from them without reconstructing; a cache the
`meniscus` command line wrote plays too; the background bake job cancels cleanly; the command-line bake works.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import subprocess
import sys
import tempfile
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check, mesh_counts  # noqa: E402

addon = _support.enable_addon()
api, cache = addon.api, addon.cache
bake, update, mesh_update = _support.addon_modules(addon, "blender.bake", "blender.update", "blender.mesh_update")

BAKED = (28, 29, 30, 31)
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_bake_")
_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()


def use_fast_settings(obj):
    """Coarse cells, few smoothing passes: the tests check the plumbing, the bake still runs the whole pipeline."""
    settings = obj.meniscus
    settings.is_surface = False
    settings.cube_size = 1.5
    settings.render_cube_size = 1.2  # what the bake uses; different from the viewport's to see which one was used
    settings.smoothing_iterations = 3
    settings.normal_smoothing_iterations = 2
    settings.output_weights = True
    settings.is_surface = True


use_fast_settings(surface)
cache_pattern = os.path.join(_temporary.name, "cache", "fluid_####.npz")


class _NoReconstruction:
    """Replaces the core's entry points while playing from a cache: any reconstruction fails the test."""

    def __enter__(self):
        self.saved = api.reconstruct, api.read_particles

        def forbidden(*_args, **_kwargs):
            raise AssertionError("reconstruction or particle reading during cache playback")

        api.reconstruct = api.read_particles = forbidden
        return self

    def __exit__(self, *_exc):
        api.reconstruct, api.read_particles = self.saved


def test_bake_operator_writes_one_file_per_frame():
    surface.meniscus.cache_pattern = cache_pattern
    scene.frame_set(29)
    # Executed (not invoked): the synchronous path that scripts and `blender -b --python-expr` take.
    result = bpy.ops.meniscus.bake(object_name=surface.name, use_surface_range=False,
                                   frame_start=BAKED[0], frame_end=BAKED[-1])
    check(result == {"FINISHED"}, result)
    folder = os.path.dirname(cache_pattern)
    names = sorted(os.listdir(folder))
    # Each frame with its provenance record (what it was made from: native/core/io/provenance.h).
    check(names == sorted([f"fluid_{frame:04d}.npz{record}" for frame in BAKED for record in ("", ".meniscus")]), names)
    check(surface.meniscus.use_cache, "after a bake the surface should play from the cache")
    check("fluid_0029.npz (cache)" in surface.meniscus.status, surface.meniscus.status)


def test_playback_comes_from_the_cache_and_matches_it():
    render_arguments = update.reconstruction_arguments(surface.meniscus, for_render=True, normals=True)
    with _NoReconstruction():
        for frame in (30, 28, 31, 29, 30):  # scrubbing back and forth
            scene.frame_set(frame)
            status = surface.meniscus.status
            check(not surface.meniscus.status_is_error and f"fluid_{frame:04d}.npz (cache)" in status, status)
            stored = cache.load_mesh(cache_pattern.replace("####", f"{frame:04d}"))
            mesh = surface.data
            check(np.array_equal(mesh_update.read_vertices(mesh), stored.vertices), f"frame {frame}: vertices differ")
            check(np.array_equal(mesh_update.read_triangles(mesh), stored.triangles), f"frame {frame}: triangles differ")
            velocity = mesh_update.read_point_vectors(mesh, "velocity")
            check(velocity is not None and np.allclose(velocity, stored.attributes["velocity"]), "velocity not played")
            weights = mesh_update.read_point_values(mesh, "weights")
            check(weights is not None and np.allclose(weights, stored.attributes["weights"]), "weights not played")
            check(mesh.has_custom_normals, "cached normals not used as custom normals")
    # A frame the partial bake left out is rebuilt from its particle file (it used to go blank).
    scene.frame_set(33)
    check(mesh_counts(surface)[1] > 0 and not surface.meniscus.status_is_error and
          "double_dam_break_0033.vtk" in surface.meniscus.status, surface.meniscus.status)
    # The bake used the render cube size: same triangles as reconstructing the file with the render settings.
    particles = api.read_particles(os.path.join(_support.SAMPLE_DIR, "double_dam_break_0030.vtk"))
    direct = api.reconstruct(particles.positions, **render_arguments)
    check(len(direct.triangles) == len(cache.load_mesh(cache_pattern.replace("####", "0030")).triangles),
          "the bake should use the render settings")


def test_turning_the_cache_off_reconstructs_again():
    scene.frame_set(30)
    surface.meniscus.use_cache = False
    check("(cache)" not in surface.meniscus.status and "double_dam_break_0030.vtk" in surface.meniscus.status,
          surface.meniscus.status)
    surface.meniscus.use_cache = True
    check("fluid_0030.npz (cache)" in surface.meniscus.status, surface.meniscus.status)


def test_cancelled_rebake_plays_no_frame_of_the_old_parameters():
    """Issue 32, item 1: bake, change a parameter, bake again and cancel after one frame: the frames left from the
    first bake are named in the summary and rebuilt from the particles, never played from the cache as current."""
    settings = surface.meniscus
    old_size = settings.render_cube_size  # what the bake uses, not the viewport
    settings.render_cube_size = 1.3
    job, stored = bake.prepare_bake(surface, BAKED[0], BAKED[-1], scene)
    job.on_frame = lambda job_, _task, _result: job_.cancel()
    job.run()
    summary = bake.finish_bake(surface, job, stored, scene)
    check(job.cancelled and job.completed == 1, summary)
    check(f"Baked 1 of {len(BAKED)} frames" in summary and "(cancelled)" in summary and
          "3 cached frames (29-31) are from an earlier bake, made with 'Render Cube Size' 1.2, now 1.3" in summary,
          summary)
    scene.frame_set(30)
    status = settings.status
    check(not settings.status_is_error and "Stale baked frame fluid_0030.npz" in status and
          "rebuilt from the particles" in status and "double_dam_break_0030.vtk" in status, status)
    stored_30 = cache.load_mesh(cache_pattern.replace("####", "0030"))
    check(len(mesh_update.read_triangles(surface.data)) != len(stored_30.triangles), "the stale frame was played")
    with _NoReconstruction():  # the frame the cancelled bake made is current: played from the cache
        scene.frame_set(28)
        check("fluid_0028.npz (cache)" in settings.status and "Stale" not in settings.status, settings.status)
    # Back to the first bake's parameters: its frames are current again, frame 28 is the stale one.
    settings.render_cube_size = old_size
    with _NoReconstruction():
        scene.frame_set(30)
        check("fluid_0030.npz (cache)" in settings.status and "Stale" not in settings.status, settings.status)
    scene.frame_set(28)
    check("Stale baked frame fluid_0028.npz" in settings.status, settings.status)
    # Without the particle files there is nothing to rebuild from: the stale frame is refused, not played.
    particles = settings.file_pattern
    settings.render_cube_size = 1.3
    settings.file_pattern = os.path.join(_temporary.name, "moved_away", "double_dam_break_####.vtk")
    try:
        scene.frame_set(31)
        check(settings.status_is_error and mesh_counts(surface) == (0, 0) and
              "Stale baked frame fluid_0031.npz: made with 'Render Cube Size' 1.2, now 1.3; bake again" in
              settings.status, settings.status)
        settings.render_cube_size = old_size
        scene.frame_set(30)
        check(not settings.status_is_error and "fluid_0030.npz (cache)" in settings.status, settings.status)
    finally:
        settings.file_pattern = particles
        settings.render_cube_size = old_size
    # Re-bake the range so the tests after this one find a cache of the current parameters.
    check(bpy.ops.meniscus.bake(object_name=surface.name, use_surface_range=False, frame_start=BAKED[0],
                                frame_end=BAKED[-1]) == {"FINISHED"}, "re-bake")


def test_background_job_reports_progress_and_cancels():
    frames = update.available_frames(surface)
    target = os.path.join(_temporary.name, "cancelled", "c_####.ply")
    tasks = [cache.BakeTask(f, frames[f], target.replace("####", f"{f:04d}")) for f in range(20, 26)]
    arguments = update.reconstruction_arguments(surface.meniscus, for_render=True, normals=True)
    seen = []

    def cancel_after_first(job, task, result):
        seen.append((task.frame, job.completed, result is not None))
        job.cancel()

    job = cache.BakeJob(tasks, arguments, on_frame=cancel_after_first).start()
    check(job.wait(timeout=120), "the bake thread did not finish")
    check(job.done and job.cancelled and job.completed == 1, f"cancel after one frame: {job.completed} done")
    check(seen == [(20, 1, True)], seen)
    check(sorted(os.listdir(os.path.dirname(target))) == ["c_0020.ply", "c_0020.ply.meniscus"],
          os.listdir(os.path.dirname(target)))
    check(not job.failures, job.failures)


def test_broken_frame_is_skipped_not_fatal():
    broken = os.path.join(_temporary.name, "broken_0001.vtk")
    with open(broken, "wb") as stream:
        stream.write(b"# vtk DataFile Version 4.0\ngarbage")
    good = os.path.join(_support.SAMPLE_DIR, "double_dam_break_0020.vtk")
    out = os.path.join(_temporary.name, "mixed", "m_{}.npz")
    tasks = [cache.BakeTask(1, broken, out.format(1)), cache.BakeTask(2, good, out.format(2))]
    job = cache.BakeJob(tasks, update.reconstruction_arguments(surface.meniscus, True)).run()
    check(list(job.failures) == [1] and job.completed == 2, job.failures)
    check(sorted(os.listdir(os.path.dirname(out))) == ["m_2.npz", "m_2.npz.meniscus"], os.listdir(os.path.dirname(out)))


def _meniscus_cli():
    return _support.COMMAND_LINE if os.path.isfile(_support.COMMAND_LINE) else None


def test_cache_written_by_the_command_line_plays():
    folder = os.path.join(_temporary.name, "cli")
    os.makedirs(folder)
    cli = _meniscus_cli()
    if cli is not None:
        subprocess.run([cli, "reconstruct", str(_support.SAMPLE_DIR / "double_dam_break_00{}.vtk"),
                        "-o", os.path.join(folder, "surface_{}.ply"), "-r", "0.025", "-c", "1.5",
                        "-s", "30", "-e", "32", "-a", "velocity", "--mesh-smoothing-iters", "2"],
                       check=True, stdout=subprocess.DEVNULL)
    else:  # no CLI built: the same files through the API, so the player is still tested
        print("     (no build/bin/meniscus: writing the PLY cache through the API)")
        for frame in (30, 31, 32):
            particles = api.read_particles(_support.SAMPLE_DIR / f"double_dam_break_00{frame}.vtk")
            api.reconstruct(particles.positions, 0.025, cube_size=1.5,
                            attributes={"velocity": particles.attributes["velocity"]}).write(
                os.path.join(folder, f"surface_{frame}.ply"))
    check(sorted(name for name in os.listdir(folder) if not name.endswith(".meniscus")) ==
          ["surface_30.ply", "surface_31.ply", "surface_32.ply"], os.listdir(folder))
    result = bpy.ops.meniscus.add_cache(filepath=os.path.join(folder, "surface_30.ply"))
    check(result == {"FINISHED"}, result)
    played = bpy.context.view_layer.objects.active
    check(played.meniscus.use_cache and (played.meniscus.frame_start, played.meniscus.frame_end) == (30, 32),
          (played.meniscus.frame_start, played.meniscus.frame_end))
    surface.meniscus.is_surface = False  # its frames outside its bake (32) would reconstruct, this test forbids it
    with _NoReconstruction():
        for frame in (31, 32, 30):
            scene.frame_set(frame)
            stored = api.read_mesh(os.path.join(folder, f"surface_{frame}.ply"))
            check(mesh_counts(played) == (len(stored.vertices), len(stored.triangles)) and len(stored.triangles) > 0,
                  f"frame {frame}: {mesh_counts(played)} vs {len(stored.vertices), len(stored.triangles)}; "
                  f"{played.meniscus.status}")
            check(mesh_update.read_point_vectors(played.data, "velocity") is not None, "PLY velocity not played")
        # Past the cache's end and no particle files to fall back on: an empty mesh and a clear message.
        played.meniscus.frame_end = 33
        scene.frame_set(33)
        check(mesh_counts(played) == (0, 0) and "Missing baked frame" in played.meniscus.status,
              played.meniscus.status)
    surface.meniscus.is_surface = True
    bpy.data.objects.remove(played)


def test_command_line_bake_of_a_saved_blend():
    # The render-farm path: a saved .blend baked by a separate, windowless process.
    blend = os.path.join(_temporary.name, "farm.blend")
    surface.meniscus.cache_pattern = os.path.join(_temporary.name, "farm", "farm_####.npz")
    surface.meniscus.use_cache = False
    bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True)
    # The node has the add-on because the user enabled it once and Blender saved the preferences (install.py did);
    # nothing here puts it on the path by hand.
    code = (f"import bpy; r = bpy.ops.meniscus.bake(object_name={surface.name!r}, use_surface_range=False, "
            f"frame_start=34, frame_end=35); print('RESULT', r); bpy.ops.wm.save_mainfile()")
    if _support.AS_MODULE:
        # A pipeline script on the bpy module starts with factory settings and enables the add-on by name
        # (reading the saved preferences instead crashes the 4.2 module, with or without add-ons).
        # os._exit: a bpy module process can hang or crash while tearing down at exit (see _support).
        command = [sys.executable, "-c", f"import bpy, addon_utils, os, sys; "
                   f"addon_utils.enable({_support.addon_module_name()!r}, default_set=True); "
                   f"bpy.ops.wm.open_mainfile(filepath={blend!r}); " + code + "; sys.stdout.flush(); os._exit(0)"]
    else:
        command = [bpy.app.binary_path, "-b", blend, "--python-expr", code]
    completed = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
    output = completed.stdout
    check("RESULT {'FINISHED'}" in output, output[-2000:])
    check("Baked 2 of 2 frames" in output, output[-2000:])
    names = sorted(name for name in os.listdir(os.path.join(_temporary.name, "farm")) if not name.endswith(".meniscus"))
    check(names == ["farm_0034.npz", "farm_0035.npz"], names)


def test_bake_refuses_what_it_cannot_do():
    surface.meniscus.cache_pattern = ""
    if not bpy.data.is_saved:
        # An unsaved .blend has no default cache folder: the bake must refuse, not write somewhere odd. Scripts see
        # an operator's error report as a RuntimeError.
        try:
            bpy.ops.meniscus.bake(object_name=surface.name)
        except RuntimeError as error:
            check("Save the .blend first" in str(error), str(error))
        else:
            raise AssertionError("bake without a cache folder should fail")
    surface.meniscus.cache_pattern = cache_pattern
    try:
        bake.prepare_bake(surface, 500, 510)
    except bake.BakeError as error:
        check("No particle files" in str(error), str(error))
    else:
        raise AssertionError("a range without files should be refused")
    # Issue 32, item 7: a range of two thousand million frames costs what its files cost, not a loop over its numbers.
    started = time.perf_counter()
    job, _stored = bake.prepare_bake(surface, -2 ** 31, 2 ** 31 - 1)
    check(job.total == len(update.available_frames(surface)) and time.perf_counter() - started < 5,
          (job.total, time.perf_counter() - started))


def test_unwritable_cache_is_refused_before_any_frame_and_killed_bakes_are_cleaned():
    """Issue 32, item 8: a cache folder that cannot be written costs a message, not a bake of lost frames; the
    temporary files of a killed bake go the next time the folder is baked into (a live writer's stay)."""
    blocker = os.path.join(_temporary.name, "a_file")
    with open(blocker, "w") as stream:
        stream.write("not a folder")
    surface.meniscus.cache_pattern = os.path.join(blocker, "cache", "fluid_####.npz")
    with _NoReconstruction():
        try:
            bpy.ops.meniscus.bake(object_name=surface.name, use_surface_range=False, frame_start=28, frame_end=29)
        except RuntimeError as error:
            check("Cache Files: cannot write to" in str(error) and "a_file" in str(error), str(error))
        else:
            raise AssertionError("a bake into an unwritable folder should be refused")
    folder = os.path.join(_temporary.name, "killed")
    os.makedirs(folder)
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()  # a process id that is no longer alive
    left = [f"fluid_0028.partial{dead.pid}.npz", f".partial-{dead.pid}-fluid_0029.npz"]
    live = f"fluid_0030.partial{os.getpid()}.npz"
    old = time.time() - cache.ABANDONED_AFTER_SECONDS - 60  # untouched since: not another machine's live write
    for name in left + [live]:
        open(os.path.join(folder, name), "wb").close()
        os.utime(os.path.join(folder, name), (old, old))
    surface.meniscus.cache_pattern = os.path.join(folder, "fluid_####.npz")
    check(bpy.ops.meniscus.bake(object_name=surface.name, use_surface_range=False, frame_start=28,
                                frame_end=28) == {"FINISHED"}, "bake")
    names = sorted(os.listdir(folder))
    check(names == sorted(["fluid_0028.npz", "fluid_0028.npz.meniscus", live]), names)
    surface.meniscus.cache_pattern = cache_pattern


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
