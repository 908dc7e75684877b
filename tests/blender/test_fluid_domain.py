"""A Mantaflow liquid domain as a source, and no silent wrong surface from any object source.

The domain's particles come from its cache files (data/pp_####.uni, read by the core), never from what the domain
shows: hidden from renders, outside the bake or with FLIP display off (all three the default of a bake: the domain
then shows its box or Mantaflow's own mesh) it gives the cache's particles or a clear error, which a final render
treats as "If a Frame Fails" says. An emitter with no live particles and a mesh with faces are refused too.

Uses the pool scene baked by tests/mantaflow/bake.sh (Debian's Blender 3.4; baked here when missing). Blender 3.4
opens the baked scene.blend and loads the cache itself; the PyPI bpy modules cannot load Mantaflow caches, so there
the same domain is rebuilt in a new scene pointing at the baked cache, which the add-on reads on its own.
"""
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check, mesh_counts  # noqa: E402

BUILD = pathlib.Path(os.environ.get("MENISCUS_BUILD", _support.REPO / "build"))
BAKE = BUILD / "mantaflow" / "pool_UNI"
VDB_BAKE = BUILD / "mantaflow" / "pool_OPENVDB"  # the same scene with Blender's default data format
if not (BAKE / "scene.json").is_file() or not (VDB_BAKE / "scene.json").is_file():  # keeps what is up to date
    subprocess.run(["bash", str(_support.REPO / "tests/mantaflow/bake.sh"), "/usr/bin/blender"], check=True,
                   env=dict(os.environ, MENISCUS_BUILD=str(BUILD)))
SCENE = json.loads((BAKE / "scene.json").read_text())
CELL = 2.0 / SCENE["resolution_max"]  # the pool's domain is 2 m along its longest side

addon = _support.enable_addon()
fluid_domain, update = _support.addon_modules(addon, "blender.fluid_domain", "blender.update")
api = update.api  # the core library as the add-on imports it (a wheel in the extension, bundled in the legacy zip)

# A copy beside its .blend: the domain's cache folder is '//cache', resolved from the .blend as Blender does.
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_fluid_domain_")
COPY = pathlib.Path(_temporary.name) / "pool"
shutil.copytree(BAKE, COPY)
OUT = pathlib.Path(_temporary.name) / "out"


def open_domain_scene():
    """The baked pool with its domain; the cache as Blender would load it (3.4) or only on disk (bpy modules)."""
    if not _support.AS_MODULE:
        bpy.ops.wm.open_mainfile(filepath=str(COPY / "scene.blend"))
        return bpy.context.scene, bpy.data.objects["Liquid Domain"]
    return _support.rebuilt_pool_domain(COPY, SCENE["frames"], SCENE["resolution_max"])


scene, domain = open_domain_scene()
# What Blender's defaults did in the bake: the domain shows its box or Mantaflow's mesh, never particles.
if not _support.AS_MODULE:
    check(not fluid_domain.domain_settings(domain).use_flip_particles, "the bake should leave FLIP display off")
domain.hide_render = True  # what artists do to hide the domain's box
bpy.context.view_layer.objects.active = domain
check(bpy.ops.meniscus.add_fluid_domain_surface() == {"FINISHED"}, "Surface From Fluid Domain refused the pool")
surface = bpy.context.view_layer.objects.active
settings = surface.meniscus
settings.smoothing_iterations = 0  # what is read matters here, not the smoothing
settings.cube_size = settings.render_cube_size = 1.5
_support.make_small_render(scene, str(OUT / "frame_####"))


def particles_of(frame):
    return api.read_particles(COPY / "cache" / "data" / f"pp_{frame:04d}.uni")


def test_surface_from_fluid_domain_reads_the_cache():
    scene.frame_set(10)
    status = settings.status
    check(not settings.status_is_error and "pp_0010.uni" in status, status)
    expected = particles_of(10)
    check(f"{len(expected):,} particles" in status, f"{status} (the cache has {len(expected):,})")
    # Around the pool's water, not the domain's box: inside the domain and well under its 1.5 m top.
    vertices = np.array([v.co for v in surface.data.vertices])
    check(len(vertices) > 1000, f"{len(vertices)} vertices")
    check(vertices[:, 2].min() > -0.1 and vertices[:, 2].max() < 1.3, (vertices.min(axis=0), vertices.max(axis=0)))
    check(np.allclose(vertices.min(axis=0)[:2], expected.positions.min(axis=0)[:2], atol=2 * CELL),
          (vertices.min(axis=0), expected.positions.min(axis=0)))


def test_defaults_derive_from_the_domain_grid_and_the_panel_says_from_what():
    # Mantaflow seeds 2 particles per cell along each axis (Particle Sampling): a radius of their spacing.
    check(abs(settings.particle_radius - CELL / 2) < 1e-6, settings.particle_radius)
    check(abs(settings.iso_threshold - fluid_domain.MANTAFLOW_ISO_THRESHOLD) < 1e-6, settings.iso_threshold)
    lines = "\n".join(fluid_domain.describe(domain))
    check("Resolution 32" in lines and "Particle Sampling 2" in lines and "0.0625" in lines, lines)
    check(str(COPY / "cache") in lines, lines)
    # The artist's scene is theirs: the domain's visibility is changed only on request.
    domain.hide_render = False
    bpy.context.view_layer.objects.active = domain
    check(bpy.ops.meniscus.add_fluid_domain_surface() == {"FINISHED"}, "second surface")
    check(not domain.hide_render, "Surface From Fluid Domain hid the domain unasked")
    second = bpy.context.view_layer.objects.active
    bpy.data.objects.remove(second, do_unlink=True)
    bpy.context.view_layer.objects.active = domain
    check(bpy.ops.meniscus.add_fluid_domain_surface(hide_domain_in_renders=True) == {"FINISHED"}, "third surface")
    check(domain.hide_render, "Hide Domain in Renders was asked for")
    bpy.data.objects.remove(bpy.context.view_layer.objects.active, do_unlink=True)
    # Surface From Object on the domain gets the same defaults.
    bpy.context.view_layer.objects.active = domain
    check(bpy.ops.meniscus.add_object_surface() == {"FINISHED"}, "Surface From Object on the domain")
    by_object = bpy.context.view_layer.objects.active
    check(abs(by_object.meniscus.particle_radius - CELL / 2) < 1e-6, by_object.meniscus.particle_radius)
    check("pp_0010.uni" in by_object.meniscus.status, by_object.meniscus.status)
    bpy.data.objects.remove(by_object, do_unlink=True)


def test_frame_offset_shifts_the_cache_frames():
    fluid_domain.domain_settings(domain).cache_frame_offset = 5
    try:
        scene.frame_set(15)
        check("pp_0010.uni" in settings.status, settings.status)
        scene.frame_set(3)  # cache frame -2: before the bake
        check(settings.status_is_error and "cache frame -2" in settings.status and "Frame Offset 5" in
              settings.status, settings.status)
    finally:
        fluid_domain.domain_settings(domain).cache_frame_offset = 0


def test_a_frame_outside_the_bake_is_an_error_not_the_domain_box():
    scene.frame_set(SCENE["frames"] + 6)
    status = settings.status
    check(settings.status_is_error, f"no error outside the bake: {status}")
    check("Missing fluid particles" in status and f"outside the domain's cache frames 1-{SCENE['frames']}" in status
          and f"pp_{SCENE['frames'] + 6:04d}.uni" in status, status)
    check(mesh_counts(surface) == (0, 0), f"a surface was left: {mesh_counts(surface)}")


def test_the_fluid_domain_for_the_narrow_band_fill():
    # A domain of its own with an open top: editing the baked domain's settings makes Blender delete its cache.
    bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 0.75))
    open_top = bpy.context.active_object
    modifier = open_top.modifiers.new("Fluid", "FLUID")
    modifier.show_viewport = modifier.show_render = False  # nothing to simulate: only its settings are read
    modifier.fluid_type = "DOMAIN"
    modifier.domain_settings.domain_type = "LIQUID"
    modifier.domain_settings.cache_directory = str(pathlib.Path(_temporary.name) / "open_top_cache")
    modifier.domain_settings.use_collision_border_top = False
    depsgraph = bpy.context.evaluated_depsgraph_get()
    built = fluid_domain.fluid_domain(open_top, scene, depsgraph, placement={"resolution": [32, 32, 24]})
    # Without gravity the fill has no down: said in the panel's terms, not the core's.
    scene.use_gravity = False
    modifier.domain_settings.gravity = (0.0, 0.0, 0.0)
    try:
        fluid_domain.fluid_domain(open_top, scene, depsgraph)
        check(False, "zero gravity was accepted")
    except fluid_domain.DomainError as error:
        check("has no gravity" in str(error) and "domain's Gravity" in str(error), str(error))
    finally:
        scene.use_gravity = True
    bpy.data.objects.remove(open_top, do_unlink=True)
    check(built["resolution"] == [32, 32, 24], "the reader's placement was dropped")
    check(built["closed_borders"] == [True] * 5 + [False], built["closed_borders"])
    check(np.allclose(built["gravity"], [0, 0, -1]), built["gravity"])
    check(built["band_width_cells"] == SCENE["particle_band_width"], built["band_width_cells"])
    # The Mesh panel's settings at Blender's defaults (bake_scene.py leaves them), for Mantaflow's own surface.
    check([built[k] for k in ("mesh_upres", "mesh_particle_radius", "mesh_smoothen_pos", "mesh_smoothen_neg")] == [2, 2.0, 1, 1], built)
    check(abs(built["mesh_concave_lower"] - 0.4) < 1e-6 and built["mesh_concave_upper"] == 3.5, built)
    # One obstacle, the 0.4 m box at (0.5, 0.3, 0.25): 12 triangles in world space.
    check(len(built["obstacles"]) == 1 and len(built["obstacles"][0]) == 12 * 9, [len(o) for o in built["obstacles"]])
    corners = np.array(built["obstacles"][0]).reshape(-1, 3)
    check(np.allclose(corners.min(axis=0), [0.3, 0.1, 0.05], atol=1e-5) and
          np.allclose(corners.max(axis=0), [0.7, 0.5, 0.45], atol=1e-5), (corners.min(axis=0), corners.max(axis=0)))


def test_openvdb_cache_is_read_from_its_fluid_data_files():
    # Blender's default data format keeps the particles in data/fluid_data_####.vdb (a point data grid).
    bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 0.75))
    vdb_domain = bpy.context.active_object
    vdb_domain.scale = (1, 1, 0.75)
    modifier = vdb_domain.modifiers.new("Fluid", "FLUID")
    modifier.show_viewport = modifier.show_render = False  # only the files are read: no Mantaflow run
    modifier.fluid_type = "DOMAIN"
    vdb_settings = modifier.domain_settings
    vdb_settings.domain_type = "LIQUID"
    vdb_settings.cache_data_format, vdb_settings.cache_type = "OPENVDB", "ALL"
    vdb_settings.cache_frame_start, vdb_settings.cache_frame_end = 1, SCENE["frames"]
    # A copy, named last: editing a domain's cache settings makes Blender delete the files of its cache folder.
    copy = pathlib.Path(_temporary.name) / "pool_vdb_cache"
    shutil.copytree(VDB_BAKE / "cache", copy)
    vdb_settings.cache_directory = str(copy)
    vdb_surface = None
    try:
        scene.frame_set(10)
        check(bpy.ops.meniscus.add_object_surface(source_name=vdb_domain.name) == {"FINISHED"}, "add")
        vdb_surface = bpy.context.view_layer.objects.active
        status = vdb_surface.meniscus.status
        expected = api.read_particles(copy / "data" / "fluid_data_0010.vdb")
        check(not vdb_surface.meniscus.status_is_error and "fluid_data_0010.vdb" in status and
              f"{len(expected):,} particles" in status, status)
        check(mesh_counts(vdb_surface)[1] > 1000, mesh_counts(vdb_surface))
    finally:
        if vdb_surface is not None:
            bpy.data.objects.remove(vdb_surface, do_unlink=True)
        bpy.data.objects.remove(vdb_domain, do_unlink=True)


def render_saved_copy(policy, first, last=None):
    settings.render_failure = policy
    blend = str(COPY / f"{policy.lower()}.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True)
    shutil.rmtree(OUT, ignore_errors=True)
    completed = _support.render_in_new_process(blend, first, last, report=f"bpy.data.objects[{surface.name!r}]")
    written = sorted(os.listdir(OUT)) if OUT.is_dir() else []
    reports = [line.split(" ", 1)[1] for line in completed.stdout.splitlines() if line.startswith("RENDERED ")]
    return completed.returncode, completed.stdout, written, reports


def test_render_of_the_hidden_domain_surfaces_the_cache_and_fails_outside_the_bake():
    last = SCENE["frames"]
    status, output, written, reports = render_saved_copy("EMPTY", last, last + 1)
    check(status == 0 and written == [f"frame_{last:04d}.png", f"frame_{last + 1:04d}.png"],
          f"exit status {status}, images {written}:\n{output[-3000:]}")
    check(len(reports) == 2, reports)
    check(f"pp_{last:04d}.uni" in reports[0] and int(reports[0].rsplit(" ", 1)[1]) > 1000, reports)
    check("Missing fluid particles" in reports[1] and reports[1].endswith(" 0"), reports)
    status, output, written, _ = render_saved_copy("STOP", last + 1)
    check(status == 1 and written == [], f"exit status {status}, images {written}:\n{output[-3000:]}")
    check(f"pp_{last + 1:04d}.uni" in output and "render stopped" in output, output[-3000:])
    # Hold Last Good Frame: the nearest earlier frame of the bake.
    status, output, written, reports = render_saved_copy("HOLD", last + 1)
    check(status == 0 and written == [f"frame_{last + 1:04d}.png"], f"exit status {status}, images {written}:\n"
          f"{output[-3000:]}")
    check(len(reports) == 1 and reports[0].startswith(f"Holding pp_{last:04d}.uni") and
          int(reports[0].rsplit(" ", 1)[1]) > 1000, reports)


def test_an_emitter_without_live_particles_is_not_its_mesh():
    bpy.ops.mesh.primitive_plane_add(size=0.6, location=(3.0, 0.0, 1.0))
    emitter = bpy.context.active_object
    emitter.modifiers.new("Particles", "PARTICLE_SYSTEM")
    emitter.particle_systems[0].settings.frame_start = emitter.particle_systems[0].settings.frame_end = 50
    scene.frame_set(2)
    check(bpy.ops.meniscus.add_object_surface(source_name=emitter.name, particle_radius=0.05) == {"FINISHED"}, "add")
    emitted = bpy.context.view_layer.objects.active
    check(emitted.meniscus.status_is_error and "has no particles at frame 2" in emitted.meniscus.status,
          emitted.meniscus.status)
    check(mesh_counts(emitted) == (0, 0), f"the emitter's corners were surfaced: {mesh_counts(emitted)}")


def test_a_mesh_with_faces_is_not_particles():
    bpy.ops.mesh.primitive_cube_add(size=1, location=(3.0, 3.0, 1.0))
    cube = bpy.context.active_object
    check(bpy.ops.meniscus.add_object_surface(source_name=cube.name, particle_radius=0.05) == {"FINISHED"}, "add")
    cornered = bpy.context.view_layer.objects.active
    status = cornered.meniscus.status
    check(cornered.meniscus.status_is_error and "6 faces" in status and "8 vertices" in status, status)
    check(mesh_counts(cornered) == (0, 0), f"the cube's corners were surfaced: {mesh_counts(cornered)}")


_support.run(globals(), cleanup=addon.unregister)
