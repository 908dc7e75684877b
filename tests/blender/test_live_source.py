"""Live source: a surface around another object's particles, evaluated at the current frame (mesh vertices and a
particle system), rebuilt when the source changes, skipped on motion-blur subframes.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check, mesh_counts  # noqa: E402

addon = _support.enable_addon()
update, mesh_update = _support.addon_modules(addon, "blender.update", "blender.mesh_update")

RADIUS = 0.05
_support.clear_scene()
scene = bpy.context.scene


def block_of_points(name, count=(8, 8, 6), spacing=2 * RADIUS):
    """A mesh of loose vertices on a lattice, like a block of fluid particles at rest."""
    axes = [np.arange(n) * spacing for n in count]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(points))
    mesh.vertices.foreach_set("co", points.astype(np.float32).reshape(-1))
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj, points


def add_surface_for(source):
    bpy.context.view_layer.objects.active = source
    result = bpy.ops.meniscus.add_object_surface(source_name=source.name, particle_radius=RADIUS)
    check(result == {"FINISHED"}, result)
    surface = bpy.context.view_layer.objects.active
    settings = surface.meniscus
    settings.is_surface = False
    settings.cube_size = settings.render_cube_size = 1.0
    # Light smoothing, two of the paper's iterations: these sources are a few hundred particles, about 12 r across,
    # which the default reach (8.56 r at cube size 1) would round off into a blob.
    settings.smoothing_iterations, settings.smoothing_reach = 2, 0.0
    settings.is_surface = True
    return surface


source, lattice = block_of_points("Points")
surface = add_surface_for(source)


def test_mesh_vertices_are_surfaced():
    scene.frame_set(1)
    check(not surface.meniscus.status_is_error, surface.meniscus.status)
    check("mesh vertices" in surface.meniscus.status and f"{len(lattice):,} particles" in surface.meniscus.status,
          surface.meniscus.status)
    vertices = mesh_update.read_vertices(surface.data)
    check(len(vertices) > 100, f"{len(vertices)} vertices")
    # The surface wraps the block: its bounds are the lattice's, grown by about a particle radius or two.
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    check(np.all(low < lattice.min(axis=0)) and np.all(high > lattice.max(axis=0)), (low, high))
    check(np.all(low > lattice.min(axis=0) - 4 * RADIUS) and np.all(high < lattice.max(axis=0) + 4 * RADIUS),
          (low, high))


def test_moving_the_source_moves_the_surface():
    before = mesh_update.read_vertices(surface.data).mean(axis=0)
    source.location.x += 1.0  # world space: the source's transform applies to its particles
    bpy.context.view_layer.update()  # the depsgraph update handler sees the source change
    after = mesh_update.read_vertices(surface.data).mean(axis=0)
    check(abs((after - before)[0] - 1.0) < 1e-3, f"surface moved by {after - before}")
    source.location.x -= 1.0
    scene.frame_set(2)  # and a frame change re-reads it too
    check(abs(mesh_update.read_vertices(surface.data).mean(axis=0)[0] - before[0]) < 1e-3, "not moved back")


def test_unchanged_source_and_subframes_do_not_rebuild():
    scene.frame_set(3)
    check(not update.update_surface(surface, scene), "an unchanged source must not be rebuilt")
    scene.frame_set(3, subframe=0.25)
    check(not update.update_surface(surface, scene), "a shutter subframe must not rebuild a live source")
    scene.frame_set(3)


def test_missing_source_object_is_reported():
    surface.meniscus.source_object = None
    check(surface.meniscus.status_is_error and "No source object" in surface.meniscus.status, surface.meniscus.status)
    check(mesh_counts(surface) == (0, 0), "no source, no surface")
    surface.meniscus.source_object = source
    check(mesh_counts(surface)[0] > 0, surface.meniscus.status)


def test_particle_system_is_surfaced():
    bpy.ops.mesh.primitive_plane_add(size=0.6, location=(3.0, 0.0, 1.0))
    emitter = bpy.context.active_object
    emitter.modifiers.new("Particles", "PARTICLE_SYSTEM")
    particle_settings = emitter.particle_systems[0].settings
    particle_settings.count = 400
    particle_settings.frame_start, particle_settings.frame_end = 1, 5
    particle_settings.lifetime = 100
    particle_settings.normal_factor = 0.5  # an upward jet
    particle_surface = add_surface_for(emitter)
    for frame in range(1, 9):  # particle systems are simulated frame by frame from the start
        scene.frame_set(frame)
    status = particle_surface.meniscus.status
    check(not particle_surface.meniscus.status_is_error and "particle system" in status, status)
    check("400 particles" in status, status)
    check(mesh_counts(particle_surface)[1] > 0, status)
    velocity = mesh_update.read_point_vectors(particle_surface.data, "velocity")
    check(velocity is not None and np.linalg.norm(velocity, axis=1).max() > 0.01, "particle velocities missing")
    # The surface wraps the particles (as evaluated now), not the emitter's own flat mesh.
    evaluated = emitter.evaluated_get(bpy.context.evaluated_depsgraph_get())
    locations = np.array([particle.location for particle in evaluated.particle_systems[0].particles])
    vertices = mesh_update.read_vertices(particle_surface.data)
    check(np.all(vertices.min(axis=0) < locations.min(axis=0)) and np.all(vertices.max(axis=0) > locations.max(axis=0)),
          f"surface {vertices.min(axis=0)}..{vertices.max(axis=0)} vs particles {locations.min(axis=0)}..{locations.max(axis=0)}")
    check(np.ptp(locations[:, 2]) > 0.05, "the particles should have moved off the emitter plane")


_support.run(globals(), cleanup=addon.unregister)
