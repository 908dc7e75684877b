"""Export Farm Job: the surface's frames and settings as an Open Job Description bundle with its parameters file;
the surface then plays the job's output folder, which the built `meniscus` command line fills here as a farm's
tasks would (`reconstruct --parameters FILE --frames A-B`).

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import json
import os
import subprocess
import sys
import tempfile
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check, mesh_counts  # noqa: E402

addon = _support.enable_addon()
FRAMES = (20, 21)
CLI = _support.COMMAND_LINE
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_farm_")
_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()
job_folder = os.path.join(_temporary.name, "job")


def _configure():
    settings = surface.meniscus
    settings.is_surface = False
    settings.frame_start, settings.frame_end = FRAMES
    settings.render_cube_size = 1.2  # what the job must carry (the bake's resolution), not the viewport's
    settings.cube_size = 1.5
    settings.smoothing_iterations = 3
    settings.smoothing_reach = 0.0  # the 3 iterations instead of the heat flow: quick
    settings.cache_pattern = os.path.join(_temporary.name, "cache", "fluid_####.npz")
    settings.is_surface = True


_configure()


def test_export_writes_the_bundle_and_the_parameters_file():
    result = bpy.ops.meniscus.export_farm_job(object_name=surface.name, directory=job_folder, chunk_size=1,
                                              meniscus_command=CLI)
    check(result == {"FINISHED"}, result)
    check(sorted(os.listdir(job_folder)) == ["asset_references.yaml", "parameter_values.yaml", "parameters.json",
                                             "template.yaml"], os.listdir(job_folder))
    with open(os.path.join(job_folder, "parameters.json")) as f:
        document = json.load(f)
    check((document["start"], document["end"]) == FRAMES, document)
    check(document["input"] == _support.SAMPLE_PATTERN, document["input"])
    check(document["output"] == os.path.join(_temporary.name, "cache", "fluid_####.ply"), document["output"])
    parameters = document["parameters"]
    check(parameters["cube_size"] == 1.2 and parameters["smoothing_iterations"] == 3, parameters)
    check(parameters["particle_radius"] == _support.SAMPLE_RADIUS and parameters["threads"] == 0, parameters)
    with open(os.path.join(job_folder, "template.yaml")) as f:
        template = f.read()
    check('type: "CHUNK[INT]"' in template and 'default: "20-21"' in template, template)
    settings = surface.meniscus
    check(settings.use_cache and settings.cache_pattern.endswith("fluid_####.ply"), settings.cache_pattern)


def test_surface_plays_the_meshes_the_farm_writes():
    parameters_file = os.path.join(job_folder, "parameters.json")
    for chunk in ("20", "21"):  # the bundle's two tasks, as a farm worker runs them
        started = time.perf_counter()
        result = subprocess.run([CLI, "reconstruct", "--parameters", parameters_file, "--frames", chunk, "--skip-existing",
                                 "-q"], capture_output=True, text=True, timeout=300)
        check(result.returncode == 0, result.stderr)
        print(f"task {chunk}: {time.perf_counter() - started:.1f} s")
    for frame in range(FRAMES[0], FRAMES[1] + 1):
        scene.frame_set(frame)
        status = surface.meniscus.status
        check(not surface.meniscus.status_is_error and f"fluid_{frame:04d}.ply (cache)" in status, status)
        check(mesh_counts(surface)[1] > 1000, mesh_counts(surface))


def test_reexported_job_redoes_the_frames_of_other_settings():
    """Issue 32, item 4: change a setting, export again into the same folders: the farm's earlier meshes are not
    played as current meanwhile, the job says it will redo them, and its tasks (--skip-existing) redo them."""
    settings = surface.meniscus
    settings.render_cube_size = 1.3
    scene.frame_set(20)
    check("Stale baked frame fluid_0020.ply (made with 'Render Cube Size' 1.2, now 1.3)" in settings.status, settings.status)
    check(bpy.ops.meniscus.export_farm_job(object_name=surface.name, directory=job_folder, chunk_size=1,
                                           meniscus_command=CLI) == {"FINISHED"}, "export")
    with open(os.path.join(job_folder, "parameters.json")) as f:
        survey = addon.farm.survey_outputs(json.load(f), *FRAMES)
    check(sorted(survey.stale) == list(FRAMES) and "2 frames will be redone" in survey.lines()[0], survey.lines())
    result = subprocess.run([CLI, "reconstruct", "--parameters", os.path.join(job_folder, "parameters.json"), "--frames",
                             "20-21", "--skip-existing", "-q"], capture_output=True, text=True, timeout=300)
    check(result.returncode == 0 and "2 of 2 frames redone" in result.stderr, result.stderr)
    scene.frame_set(21)
    scene.frame_set(20)
    check("fluid_0020.ply (cache)" in settings.status and "Stale" not in settings.status, settings.status)


def test_export_without_a_saved_blend_or_folder_is_refused():
    result = None
    try:
        result = bpy.ops.meniscus.export_farm_job(object_name=surface.name, directory="//farm_job")
    except RuntimeError as error:  # operators report errors as RuntimeError when called from a script
        check("Save the .blend first" in str(error), str(error))
    check(result != {"FINISHED"}, result)


_support.run(globals(), cleanup=_temporary.cleanup)
