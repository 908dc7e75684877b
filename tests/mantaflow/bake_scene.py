"""Bakes a small Mantaflow liquid scene headless (Debian's Blender 3.4; the PyPI bpy modules cannot bake).

    blender -b --factory-startup --python tests/mantaflow/bake_scene.py -- OUT_DIR [--scene pool] [--format UNI]
        [--resolution 32] [--frames 24]

Writes OUT_DIR/cache (Mantaflow's cache: data/, mesh/ with Mantaflow's own surface, config/), OUT_DIR/scene.blend
(the scene, for tests that surface the domain in Blender) and OUT_DIR/scene.json (the domain's settings). Every
setting not named here keeps Blender's default, as a new user's Quick Liquid would: FLIP particles in the default
narrow band (3 cells), particle number 2.

Scenes: `pool` (a 2 x 2 x 1.5 m closed domain, a liquid sphere falling into it, a box obstacle on the floor: the
issue's scene), `open_top` (the same with the domain's top border open), `moving_obstacle` (the box slides through
the liquid), `splash` (a thin fast jet from an inflow hitting the floor).
"""
import argparse
import json
import os
import sys
import time

import bpy


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("out")
    parser.add_argument("--scene", default="pool", choices=["pool", "open_top", "moving_obstacle", "splash"])
    parser.add_argument("--format", default="UNI", choices=["UNI", "OPENVDB"])
    parser.add_argument("--resolution", type=int, default=32)
    parser.add_argument("--frames", type=int, default=24)
    return parser.parse_args(argv)


def add_fluid(obj, fluid_type):
    modifier = obj.modifiers.new("Fluid", 'FLUID')
    modifier.fluid_type = fluid_type
    return modifier


def build_scene(args):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, args.frames

    bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 0.75))
    domain = bpy.context.active_object
    domain.name = "Liquid Domain"
    domain.scale = (1, 1, 0.75)

    if args.scene == "splash":
        bpy.ops.mesh.primitive_cylinder_add(radius=0.08, depth=0.1, location=(-0.7, 0, 1.2), rotation=(0, 1.2, 0))
        flow = bpy.context.active_object
        flow_settings = add_fluid(flow, 'FLOW').flow_settings
        flow_settings.flow_type = 'LIQUID'
        flow_settings.flow_behavior = 'INFLOW'
        flow_settings.use_initial_velocity = True
        flow_settings.velocity_coord = (4.0, 0.0, 1.0)
    else:
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.45, location=(-0.3, 0, 1.0))
        flow = bpy.context.active_object
        flow_settings = add_fluid(flow, 'FLOW').flow_settings
        flow_settings.flow_type = 'LIQUID'
        flow_settings.flow_behavior = 'GEOMETRY'
        # A layer of water on the floor, so the pool is several band widths deep.
        bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 0.2))
        layer = bpy.context.active_object
        layer.scale = (0.99, 0.99, 0.18)
        layer_settings = add_fluid(layer, 'FLOW').flow_settings
        layer_settings.flow_type = 'LIQUID'
        layer_settings.flow_behavior = 'GEOMETRY'
        layer.hide_render = True

    bpy.ops.mesh.primitive_cube_add(size=0.4, location=(0.5, 0.3, 0.25))
    obstacle = bpy.context.active_object
    obstacle.name = "Obstacle"
    add_fluid(obstacle, 'EFFECTOR')
    if args.scene == "moving_obstacle":
        obstacle.location = (0.6, -0.5, 0.25)
        obstacle.keyframe_insert("location", frame=1)
        obstacle.location = (-0.6, 0.5, 0.25)
        obstacle.keyframe_insert("location", frame=args.frames)

    domain_settings = add_fluid(domain, 'DOMAIN').domain_settings
    domain_settings.domain_type = 'LIQUID'
    domain_settings.resolution_max = args.resolution
    domain_settings.use_flip_particles = True
    domain_settings.use_mesh = True
    domain_settings.cache_type = 'ALL'
    domain_settings.cache_frame_start = 1
    domain_settings.cache_frame_end = args.frames
    domain_settings.cache_data_format = args.format
    domain_settings.cache_directory = os.path.join(os.path.abspath(args.out), "cache")
    if args.scene == "open_top":
        domain_settings.use_collision_border_top = False
    for obj in (flow, obstacle):
        obj.select_set(False)
    bpy.context.view_layer.objects.active = domain
    return scene, domain


def bake(scene, domain):
    override = {"scene": scene, "active_object": domain, "object": domain}
    if hasattr(bpy.context, "temp_override"):
        with bpy.context.temp_override(**override):
            bpy.ops.fluid.bake_all()
    else:
        bpy.ops.fluid.bake_all(override)


def mantaflow_volumes(scene, domain):
    """The enclosed volume of Mantaflow's own surface at each frame, in world space (m^3): the reference."""
    volumes = {}
    for frame in range(scene.frame_start, scene.frame_end + 1):
        scene.frame_set(frame)
        evaluated = domain.evaluated_get(bpy.context.evaluated_depsgraph_get())
        mesh = evaluated.to_mesh()
        matrix = evaluated.matrix_world
        corners = [matrix @ v.co for v in mesh.vertices]
        total = 0.0
        mesh.calc_loop_triangles()
        for triangle in mesh.loop_triangles:
            a, b, c = (corners[i] for i in triangle.vertices)
            total += a.dot(b.cross(c)) / 6.0
        volumes[frame] = total
        evaluated.to_mesh_clear()
    return volumes


def main():
    args = arguments()
    os.makedirs(args.out, exist_ok=True)
    scene, domain = build_scene(args)
    started = time.perf_counter()
    bake(scene, domain)
    seconds = time.perf_counter() - started
    settings = domain.modifiers["Fluid"].domain_settings
    json.dump({
        "scene": args.scene, "format": args.format, "frames": args.frames, "bake_seconds": seconds,
        "resolution_max": settings.resolution_max, "particle_band_width": settings.particle_band_width,
        "particle_number": settings.particle_number, "particle_radius": settings.particle_radius,
        "domain_dimensions": list(domain.dimensions), "domain_location": list(domain.location),
        "matrix_world": [list(row) for row in domain.matrix_world],
        "open_top": not settings.use_collision_border_top,
        "mantaflow_mesh_volume": mantaflow_volumes(scene, domain),
    }, open(os.path.join(args.out, "scene.json"), "w"), indent=1)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(os.path.abspath(args.out), "scene.blend"))
    print(f"mantaflow: baked {args.scene} ({args.format}, resolution {args.resolution}, {args.frames} frames) "
          f"in {seconds:.1f} s")


main()
