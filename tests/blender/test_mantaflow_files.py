"""Mantaflow's cache files as particle sequences: the UNI particles (data/pp_####.uni) and the OpenVDB data files
(data/fluid_data_####.vdb) that Debian's Blender 3.4 baked (tests/mantaflow/bake.sh, run by the test command before
this suite) surface in every Blender version through Add Particle Sequence, inside the domain.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check, mesh_counts  # noqa: E402

addon = _support.enable_addon()
operators, mesh_update = _support.addon_modules(addon, "blender.operators", "blender.mesh_update")
BAKES = pathlib.Path(os.environ.get("MENISCUS_BUILD", _support.REPO / "build")) / "mantaflow"
_support.clear_scene()
scene = bpy.context.scene


def surface_of(path):
    check(path.is_file(), f"{path} is missing: run tests/mantaflow/bake.sh first")
    surface = _support.add_sample_sequence(str(path))  # radius 0.025 m: 0.4 cells of the 32-cell pool
    settings = surface.meniscus
    settings.is_surface = False
    settings.cube_size = 0.75
    settings.render_cube_size = 0.75
    settings.smoothing_iterations = 0
    settings.is_surface = True
    return surface


def check_pool_surface(surface, name):
    settings = surface.meniscus
    check((settings.frame_start, settings.frame_end) == (1, 24), f"frame range {settings.frame_start}-{settings.frame_end}")
    scene.frame_set(10)
    vertices, triangles = mesh_counts(surface)
    check(vertices > 1000 and triangles > 1000, f"{name}: surface {vertices} / {triangles}: {settings.status}")
    check(not settings.status_is_error and name in settings.status, settings.status)
    world = np.asarray(mesh_update.read_vertices(surface.data), dtype=np.float64)
    low, high = world.min(axis=0), world.max(axis=0)
    # Placed by the cache's config: inside the 2 x 2 x 1.5 m domain on the floor, not in grid cells (0..32).
    check(low[2] > -0.1 and high[2] < 1.6 and np.abs(world[:, :2]).max() < 1.1, f"{name}: bounds {low} .. {high}")


def test_the_file_browser_offers_the_cache_files():
    for extension in ("*.uni", "*.vdb"):
        check(extension in operators.PARTICLE_FILE_GLOB.split(";"), operators.PARTICLE_FILE_GLOB)


def test_uni_particles_surface_inside_the_domain():
    surface = surface_of(BAKES / "pool_UNI/cache/data/pp_0005.uni")
    check(surface.meniscus.file_pattern.endswith("pp_####.uni"), surface.meniscus.file_pattern)
    check_pool_surface(surface, "pp_0010.uni")


def test_openvdb_particles_surface_inside_the_domain():
    surface = surface_of(BAKES / "pool_OPENVDB/cache/data/fluid_data_0005.vdb")
    check(surface.meniscus.file_pattern.endswith("fluid_data_####.vdb"), surface.meniscus.file_pattern)
    check_pool_surface(surface, "fluid_data_0010.vdb")


def _cleanup():
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
