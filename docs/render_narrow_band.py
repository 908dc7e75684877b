"""Renders the narrow-band figure in Cycles: one frame of a Mantaflow cache baked by tests/mantaflow/bake.sh, side by
side: the band's particles alone (fill_interior 0), the band filled (fill_interior on) and Mantaflow's own mesh, seen
from below the floor, where a hollow band shows.

    blender -b --factory-startup --python-exit-code 1 --python docs/render_narrow_band.py -- --addon-path build/addon \
        [--scene pool] [--frame 12] [--output docs/images/narrow_band_pool.png]
"""
import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import render_scene  # noqa: E402

args = render_scene.mantaflow_figure_arguments()

meniscus, mesh_update = render_scene.library(args.addon_path)

cache = pathlib.Path(args.bakes) / f"{args.scene}_UNI" / "cache"
particles = meniscus.read_particles(cache / f"data/pp_{args.frame:04d}.uni")
domain = {**particles.fluid_domain, "band_width_cells": 3.0}  # Blender's default band (the cache does not say)
cell = domain["axes"][0][0]
settings = dict(iso_threshold=0.45, fluid_domain=domain)  # as tests/python/test_interior_fill.py
surfaces = [("band alone", meniscus.reconstruct(particles.positions, cell / 2, fluid_surface=0, fill_interior=0, **settings)),
            ("filled", meniscus.reconstruct(particles.positions, cell / 2, fluid_surface=0, **settings)),
            ("level set", meniscus.reconstruct(particles.positions, cell / 2, fluid_domain=domain)),
            ("Mantaflow", meniscus.read_mesh(cache / f"mesh/fluid_mesh_{args.frame:04d}.bobj.gz"))]

scene = render_scene.cycles_scene(args.samples, 1440, 330)
water = render_scene.water_material()

for index, (name, mesh) in enumerate(surfaces):
    data = bpy.data.meshes.new(name)
    mesh_update.write_surface(data, np.asarray(mesh.vertices, dtype=np.float32) + np.float32([2.3 * (index - 1.5), 0, 0]),
                              np.asarray(mesh.triangles, dtype=np.int32), mesh.normals)
    for polygon in data.polygons:
        polygon.use_smooth = mesh.normals is not None
    obj = bpy.data.objects.new(name, data)
    obj.data.materials.append(water)
    scene.collection.objects.link(obj)

# In front of the four and below the floor (z = 0), looking up at their undersides.
render_scene.add_camera(scene, (0.0, -16.0, -2.0), (0.0, 0.0, 0.45), 55)
render_scene.add_sun(scene, (-70, 0, 30))
scene.render.image_settings.color_depth = "8"
scene.render.image_settings.compression = 100
scene.render.filepath = str(pathlib.Path(args.output or f"docs/images/narrow_band_{args.scene}.png").resolve())
bpy.ops.render.render(write_still=True)
print("rendered", scene.render.filepath)
