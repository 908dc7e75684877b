"""Blender (Debian's 3.4, Cycles, CPU, denoising off) renders of meshes side by side in one PNG (the README's
"Faithful at every cube size" renders; the meshes come from `bench/smoothing_scale.py meshes`).

    blender -b --factory-startup -P bench/smoothing_render.py -- OUT.png CAM_X,CAM_Y,CAM_Z TARGET_X,TARGET_Y,TARGET_Z SHIFT_X mesh1.ply mesh2.ply ...
Each mesh is shifted by SHIFT_X * its index along x, so the meshes stand side by side in one image.
"""
import sys

import bpy
from mathutils import Vector

args = sys.argv[sys.argv.index("--") + 1:]
out, cam, target, shift, meshes = args[0], [float(x) for x in args[1].split(",")], [float(x) for x in args[2].split(",")], float(args[3]), args[4:]
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 24
scene.cycles.use_denoising = False
scene.render.resolution_x, scene.render.resolution_y = 1200, 500
material = bpy.data.materials.new("water")
material.use_nodes = True
bsdf = material.node_tree.nodes["Principled BSDF"]
bsdf.inputs["Base Color"].default_value = (0.35, 0.55, 0.8, 1)
bsdf.inputs["Roughness"].default_value = 0.15
bsdf.inputs["Specular"].default_value = 0.8
for i, path in enumerate(meshes):
    bpy.ops.import_mesh.ply(filepath=path)
    obj = bpy.context.selected_objects[0]
    obj.location.x += shift * i
    obj.data.materials.append(material)
    for poly in obj.data.polygons:
        poly.use_smooth = True
camera = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
scene.collection.objects.link(camera)
camera.location = Vector(cam)
direction = Vector(target) - camera.location
camera.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
camera.data.lens = 35
scene.camera = camera
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 4.0
sun.rotation_euler = (0.6, 0.3, 0.8)
scene.collection.objects.link(sun)
world = bpy.data.worlds.new("w")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.8, 0.8, 0.85, 1)
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.6
scene.world = world
scene.render.filepath = out
bpy.ops.render.render(write_still=True)
