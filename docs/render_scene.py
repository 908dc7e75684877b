"""What the README's Cycles figures share (docs/render_figures.py, docs/render_container.py, and from a Mantaflow
cache docs/render_narrow_band.py, docs/render_fluid_domain.py): the library from the add-on folder, an emptied scene
with Cycles and a light grey sky, a camera aimed at a point, a sun, a water material."""
import argparse
import math
import pathlib
import sys

import bpy
import numpy as np


def library(addon_path):
    """(meniscus, its Blender mesh writer) from the add-on folder, as the add-on itself imports them."""
    sys.path.insert(0, str(pathlib.Path(addon_path).resolve()))
    import meniscus
    from meniscus.blender import mesh_update
    return meniscus, mesh_update


def cycles_scene(samples, width, height):
    """The current scene emptied, rendering with Cycles (no denoising: Debian's Blender has no OpenImageDenoise)."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.film_transparent = False
    world = bpy.data.worlds.new("figures") if scene.world is None else scene.world
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs[0].default_value = (0.8, 0.85, 0.9, 1.0)
    world.node_tree.nodes["Background"].inputs[1].default_value = 0.6
    return scene


def add_camera(scene, location, target, lens):
    """The scene's camera at `location`, looking at `target` with the horizon level."""
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    scene.collection.objects.link(camera)
    camera.location = tuple(location)
    direction = np.asarray(target, dtype=float) - np.asarray(location, dtype=float)
    camera.rotation_euler = (math.atan2(math.hypot(direction[0], direction[1]), -direction[2]), 0.0,
                             math.atan2(direction[1], direction[0]) - math.pi / 2)
    camera.data.lens = lens
    scene.camera = camera
    return camera


def add_sun(scene, rotation_degrees, energy=4.0):
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.energy = energy
    sun.rotation_euler = tuple(math.radians(angle) for angle in rotation_degrees)
    scene.collection.objects.link(sun)
    return sun


def mantaflow_figure_arguments():
    """The command line of the figures made from a Mantaflow cache of tests/mantaflow/bake.sh (render_narrow_band.py,
    render_fluid_domain.py): the arguments after Blender's '--'."""
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--addon-path", default="build/addon")
    parser.add_argument("--bakes", default="build/mantaflow")
    parser.add_argument("--scene", default="pool")
    parser.add_argument("--frame", type=int, default=12)
    parser.add_argument("--output", default=None)
    parser.add_argument("--samples", type=int, default=16)
    return parser.parse_args(argv)


def water_material():
    water = bpy.data.materials.new("water")
    water.use_nodes = True
    bsdf = water.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0.55, 0.65, 0.8, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.2
    return water
