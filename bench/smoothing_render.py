"""Blender (Debian's 3.4, Cycles, CPU, denoising off) renders of meshes side by side in one PNG (the README's
"Faithful at every cube size" renders; the meshes come from `bench/smoothing_scale.py meshes`).

    blender -b --factory-startup -P bench/smoothing_render.py -- OUT.png CAM_X,CAM_Y,CAM_Z TARGET_X,TARGET_Y,TARGET_Z SHIFT_X [up=X,Y,Z] mesh1.ply mesh2.ply ...
Each mesh is shifted by SHIFT_X * its index along x, so the meshes stand side by side in one image. With SHIFT_X = 0
each mesh is rendered alone through the same camera (800 x 500) and the images are put side by side: a close view of
the same place in every mesh (the dam break at c = 0.25 in README). up=X,Y,Z: the scene's up axis (the shared frames'
is y; Blender's is z, the default), which the camera keeps upright and the sun shines down along.
"""
import sys

import bpy
from mathutils import Vector

args = sys.argv[sys.argv.index("--") + 1:]
out, cam, target, shift, meshes = args[0], [float(x) for x in args[1].split(",")], [float(x) for x in args[2].split(",")], float(args[3]), args[4:]
up_axis = Vector((0.0, 0.0, 1.0))
if meshes and meshes[0].startswith("up="):
    up_axis = Vector([float(x) for x in meshes[0][3:].split(",")]).normalized()
    meshes = meshes[1:]
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
objects = []
for i, path in enumerate(meshes):
    bpy.ops.import_mesh.ply(filepath=path)
    obj = bpy.context.selected_objects[0]
    objects.append(obj)
    obj.location.x += shift * i
    obj.data.materials.append(material)
    for poly in obj.data.polygons:
        poly.use_smooth = True
camera = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
scene.collection.objects.link(camera)
camera.location = Vector(cam)
direction = Vector(target) - camera.location
if up_axis == Vector((0.0, 0.0, 1.0)):
    camera.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
else:  # look at the target with the scene's up axis at the top of the image
    from mathutils import Matrix

    back = -direction.normalized()
    side = up_axis.cross(back).normalized()
    camera.rotation_euler = Matrix((side, back.cross(side), back)).transposed().to_euler()
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
if shift != 0.0:
    scene.render.filepath = out
    bpy.ops.render.render(write_still=True)
else:
    import numpy as np

    scene.render.resolution_x = 800
    # Light from overhead (the scene's up axis), slightly from the front and side, and a dimmer sky: bumps of a
    # particle's size show on a flat pool.
    bpy.context.view_layer.update()
    forward = direction.normalized()
    right = camera.matrix_world.col[0].xyz
    sun.rotation_euler = (0.3 * forward - 0.9 * up_axis + 0.3 * right).normalized().to_track_quat("-Z", "Y").to_euler()
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.3
    panels = []
    for i, obj in enumerate(objects):
        for other in objects:
            other.hide_render = other is not obj
        scene.render.filepath = f"{out}.panel{i}.png"
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        pixels = np.empty(image.size[0] * image.size[1] * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
        panels.append(pixels.reshape(image.size[1], image.size[0], 4))
    gap = np.ones((panels[0].shape[0], 6, 4), dtype=np.float32)
    row = np.concatenate([part for panel in panels for part in (panel, gap)][:-1], axis=1)
    joined = bpy.data.images.new("joined", row.shape[1], row.shape[0], alpha=False)
    joined.pixels.foreach_set(row.reshape(-1))
    joined.filepath_raw = out
    joined.file_format = "PNG"
    joined.save()
