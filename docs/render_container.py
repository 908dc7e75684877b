"""Renders the README's container figure in Cycles: one frame of the shared dam-break sequence (box walls at
[0, 3] x [0, 1.2] x [0, 2], gravity -z) without a container (left) and with the tank as a capped mesh box (right),
seen from outside the tank's left wall (x = 0), slightly from below: there the fluid rests against the wall and
the floor.

    blender -b --factory-startup --python-exit-code 1 --python docs/render_container.py -- --addon-path build/addon
"""
import argparse
import pathlib
import sys

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser()
parser.add_argument("--addon-path", default="build/addon")
parser.add_argument("--frame", default="../shared/data/sequence/double_dam_break_0060.vtk")
parser.add_argument("--output", default="docs/images/container.png")
parser.add_argument("--samples", type=int, default=32)
args = parser.parse_args(argv)
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import render_scene  # noqa: E402

meniscus, mesh_update = render_scene.library(args.addon_path)

TANK = ((0.0, 0.0, 0.0), (3.0, 1.2, 2.0))
particles = meniscus.read_particles(args.frame)
free = meniscus.reconstruct(particles.positions, 0.025, cube_size=0.5)
tank = meniscus.reconstruct(particles.positions, 0.025, cube_size=0.5, mesh_aabb_min=TANK[0], mesh_aabb_max=TANK[1])

scene = render_scene.cycles_scene(args.samples, 1200, 500)

water = bpy.data.materials.new("water")
water.use_nodes = True
bsdf = water.node_tree.nodes["Principled BSDF"]
bsdf.inputs["Base Color"].default_value = (0.55, 0.65, 0.8, 1.0)
bsdf.inputs["Roughness"].default_value = 0.15

for name, mesh, shift in (("no container", free, 0.0), ("tank as container", tank, 1.5)):
    data = bpy.data.meshes.new(name)
    mesh_update.write_surface(data, mesh.vertices + np.float32([0, shift, 0]), mesh.triangles, mesh.normals)
    obj = bpy.data.objects.new(name, data)
    obj.data.materials.append(water)
    scene.collection.objects.link(obj)

# Outside the left wall, a little below the floor's level, looking at both surfaces' x = 0 ends side by side.
render_scene.add_camera(scene, (-3.2, 1.35, -0.35), (0.0, 1.35, 0.25), 30)
render_scene.add_sun(scene, (70, 0, -60))
scene.render.filepath = str(pathlib.Path(args.output).resolve())
bpy.ops.render.render(write_still=True)
print("rendered", scene.render.filepath)
