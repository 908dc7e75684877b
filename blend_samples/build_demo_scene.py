"""Builds the demo scene (the bundled double dam break in a tank) and renders one frame with Cycles.

    blender -b --factory-startup --python-exit-code 1 --python blend_samples/build_demo_scene.py -- \
        --addon-path build/addon --frame 30 --output /tmp/frame_0030.png [--save-blend /tmp/demo.blend]

The add-on is registered from the given folder (the staged build), not installed: the script leaves the user's
Blender preferences alone. Prints the PNG's path on the last line.
"""
import argparse
import math
import os
import pathlib
import sys
import time

import bpy
from mathutils import Vector

HERE = pathlib.Path(__file__).resolve().parent
SEQUENCE = HERE / "double_dam_break" / "double_dam_break_####.vtk"
PARTICLE_RADIUS = 0.025
# The simulation domain in metres, z up: the water is confined to this box.
DOMAIN_MIN = Vector((0.0, 0.0, 0.0))
DOMAIN_MAX = Vector((3.0, 1.2, 2.0))
WALL_THICKNESS = 0.04


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--addon-path", default=str(HERE.parent / "build" / "addon"),
                        help="folder holding the staged 'meniscus' package (default: build/addon)")
    parser.add_argument("--frame", type=int, default=30, help="frame to render (files 20-39 are bundled)")
    parser.add_argument("--output", default=str(HERE.parent / "build" / "demo" / "frame_0030.png"), help="PNG to write")
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--resolution", type=int, nargs=2, default=(640, 360), metavar=("WIDTH", "HEIGHT"))
    parser.add_argument("--save-blend", default="", help="also save the scene to this .blend")
    parser.add_argument("--no-render", action="store_true", help="build (and save) the scene only")
    return parser.parse_args(argv)


def clear_scene():
    # --factory-startup brings a cube, a camera and a light; the demo builds its own.
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for collection in (bpy.data.meshes, bpy.data.materials, bpy.data.cameras, bpy.data.lights):
        for block in list(collection):
            collection.remove(block)


def register_addon(addon_path):
    addon_path = os.path.abspath(addon_path)
    if not os.path.isdir(os.path.join(addon_path, "meniscus")):
        raise SystemExit(f"no 'meniscus' package in {addon_path} (build it first: cmake --build build)")
    sys.path.insert(0, addon_path)
    import meniscus

    meniscus.register()
    return meniscus


def add_fluid(scene):
    result = bpy.ops.meniscus.add_sequence(filepath=str(SEQUENCE), particle_radius=PARTICLE_RADIUS, relative_path=False)
    if result != {"FINISHED"}:
        raise RuntimeError(f"adding the particle sequence failed: {result}")
    surface = bpy.context.view_layer.objects.active
    scene.frame_start, scene.frame_end = surface.meniscus.frame_start, surface.meniscus.frame_end
    return surface


def _principled_material(name, color, roughness):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    principled = material.node_tree.nodes["Principled BSDF"]
    principled.inputs["Base Color"].default_value = color
    principled.inputs["Roughness"].default_value = roughness
    return material


def _tile_material():
    """Light tiles: the regular pattern seen through the water shows its refraction and makes it read as water."""
    material = _principled_material("Tank Tiles", (0.7, 0.72, 0.72, 1.0), 0.4)
    nodes, links = material.node_tree.nodes, material.node_tree.links
    coordinates = nodes.new("ShaderNodeTexCoord")
    checker = nodes.new("ShaderNodeTexChecker")  # 3D, so floor and walls get the same grid without UVs
    checker.inputs["Color1"].default_value = (0.62, 0.66, 0.68, 1.0)
    checker.inputs["Color2"].default_value = (0.42, 0.47, 0.50, 1.0)
    checker.inputs["Scale"].default_value = 5.0  # 20 cm tiles in object space (metres)
    links.new(coordinates.outputs["Object"], checker.inputs["Vector"])
    links.new(checker.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    return material


def _box(name, center, size, material, collection):
    mesh = bpy.data.meshes.new(name)
    half = [s / 2 for s in size]
    corners = [(sx * half[0], sy * half[1], sz * half[2]) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh.from_pydata(corners, [], faces)
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    obj.location = center
    collection.objects.link(obj)
    return obj


def add_tank(scene):
    """A tiled floor and the two far walls of the domain; the near walls stay open so the camera sees the water."""
    tiles = _tile_material()
    t = WALL_THICKNESS
    size = DOMAIN_MAX - DOMAIN_MIN
    middle = (DOMAIN_MIN + DOMAIN_MAX) / 2
    collection = scene.collection
    _box("Tank Floor", (middle.x, middle.y, -t / 2), (size.x + 2 * t, size.y + 2 * t, t), tiles, collection)
    _box("Tank Back Wall", (middle.x, DOMAIN_MAX.y + t / 2, 0.3 * size.z), (size.x + 2 * t, t, 0.6 * size.z), tiles,
         collection)
    _box("Tank Side Wall", (DOMAIN_MAX.x + t / 2, middle.y, 0.3 * size.z), (t, size.y, 0.6 * size.z), tiles,
         collection)
    # A large ground so that the horizon is not black and the tank does not float in the void.
    ground_material = _principled_material("Ground", (0.2, 0.2, 0.21, 1.0), 0.8)
    _box("Ground", (middle.x, middle.y, -t - 0.01), (40.0, 40.0, 0.02), ground_material, collection)


def add_lighting(scene):
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    # A soft sky: lights the water's reflections and the shadow sides; the sun gives shape and highlights.
    background.inputs["Color"].default_value = (0.62, 0.74, 0.9, 1.0)
    background.inputs["Strength"].default_value = 0.5

    sun_data = bpy.data.lights.new("Sun", "SUN")
    sun_data.energy = 3.0
    sun_data.angle = math.radians(3.0)
    sun = bpy.data.objects.new("Sun", sun_data)
    sun.rotation_euler = (math.radians(40), math.radians(-15), math.radians(-30))
    scene.collection.objects.link(sun)

    area_data = bpy.data.lights.new("Fill", "AREA")
    area_data.energy = 400.0
    area_data.size = 3.0
    area = bpy.data.objects.new("Fill", area_data)
    area.location = (-1.5, -2.5, 3.0)
    _aim(area, Vector((1.5, 0.6, 0.3)))
    scene.collection.objects.link(area)


def _aim(obj, target):
    direction = target - Vector(obj.location)
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()


def add_camera(scene):
    camera_data = bpy.data.cameras.new("Camera")
    camera_data.lens = 28.0
    camera = bpy.data.objects.new("Camera", camera_data)
    # Elevated three-quarter view from the open front-left corner, looking at the middle where the waves meet.
    camera.location = (-0.9, -2.9, 2.3)
    _aim(camera, Vector((1.55, 0.55, 0.35)))
    scene.collection.objects.link(camera)
    scene.camera = camera


def configure_render(scene, samples, width, height):
    render = scene.render
    render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False  # Debian's Blender is built without OpenImageDenoise
    # Water through few samples: caustics and unclamped indirect light are where the fireflies come from.
    scene.cycles.caustics_reflective = False
    scene.cycles.caustics_refractive = False
    scene.cycles.sample_clamp_indirect = 5.0
    scene.cycles.blur_glossy = 1.0
    scene.cycles.transmission_bounces = 12
    scene.cycles.max_bounces = 12
    render.resolution_x, render.resolution_y = width, height
    render.resolution_percentage = 100
    render.image_settings.file_format = "PNG"
    render.image_settings.color_mode = "RGB"
    scene.view_settings.view_transform = "Filmic"
    scene.view_settings.look = "Medium High Contrast"
    scene.view_settings.exposure = -0.4  # the light tiles otherwise wash out next to the clear water
    render.use_lock_interface = True


def build_scene(addon_path, samples=32, resolution=(640, 360)):
    """Clears the current scene and builds the demo in it; returns (scene, surface object). Used by render_demo.py."""
    clear_scene()
    register_addon(addon_path)
    scene = bpy.context.scene
    surface = add_fluid(scene)
    add_tank(scene)
    add_lighting(scene)
    add_camera(scene)
    configure_render(scene, samples, *resolution)
    return scene, surface


def main():
    arguments = parse_arguments()
    scene, surface = build_scene(arguments.addon_path, arguments.samples, arguments.resolution)

    scene.frame_set(arguments.frame)
    print(f"Meniscus surface at frame {arguments.frame}: {surface.meniscus.status}")
    if surface.meniscus.status_is_error or len(surface.data.polygons) == 0:
        raise RuntimeError(f"no surface at frame {arguments.frame}: {surface.meniscus.status}")

    if arguments.save_blend:
        blend = os.path.abspath(arguments.save_blend)
        bpy.ops.wm.save_as_mainfile(filepath=blend)
        # Blender's relative remapping on save knows only its own paths (images, libraries), not add-on properties:
        # make the sequence path relative ourselves, so the .blend and the sample folder can move together.
        surface.meniscus.file_pattern = bpy.path.relpath(surface.meniscus.file_pattern)
        bpy.ops.wm.save_mainfile()
        print(f"saved: {blend} (particles at {surface.meniscus.file_pattern})")
    if arguments.no_render:
        return
    output = os.path.abspath(arguments.output)
    os.makedirs(os.path.dirname(output), exist_ok=True)
    scene.render.filepath = output
    started = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    if not os.path.isfile(output):
        raise RuntimeError(f"render did not write {output}")
    print(f"rendered in {time.perf_counter() - started:.1f} s")
    print(output)


if __name__ == "__main__":  # Blender runs --python scripts as __main__; render_demo.py imports this file instead
    main()
