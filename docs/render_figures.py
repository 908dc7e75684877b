"""Renders the README's figures in Cycles, as the paper's Fig. 1/2 do: one shared frame raw (marching cubes),
smoothed (full pipeline), and the feature weights as colours (blue 0 -> red 1).

    blender -b --factory-startup --python-exit-code 1 --python docs/render_figures.py -- --addon-path build/addon
"""
import argparse
import pathlib
import sys

import bpy
import numpy as np

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
parser = argparse.ArgumentParser()
parser.add_argument("--addon-path", default="build/addon")
parser.add_argument("--frame", default="../shared/data/splashsurf/double_dam_break_frame_26_4732_particles.vtk")
parser.add_argument("--output", default="docs/images")
parser.add_argument("--samples", type=int, default=48)
args = parser.parse_args(argv)
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import render_scene  # noqa: E402

meniscus, mesh_update = render_scene.library(args.addon_path)

out = pathlib.Path(args.output)
out.mkdir(parents=True, exist_ok=True)
particles = meniscus.read_particles(args.frame)
smoothed = meniscus.reconstruct(particles.positions, 0.025, cube_size=0.5, decimate_barnacles=True,  # the default smoothing
                                normal_smoothing_iterations=10, output_weights=True, keep_raw_mesh=True)
raw = smoothed.raw
RAW = dict(decimate_barnacles=False, smoothing_iterations=0, normal_smoothing_iterations=0)  # marching cubes alone
raw_normals = meniscus.reconstruct(particles.positions, 0.025, cube_size=0.5, **RAW).normals

scene = render_scene.cycles_scene(args.samples, 960, 540)



def z_up(a):
    # SPlisHSPlasH frames are y-up; Blender is z-up: (x, y, z) -> (x, -z, y) keeps the handedness.
    return None if a is None else np.ascontiguousarray(np.stack([a[:, 0], -a[:, 2], a[:, 1]], axis=1), dtype=np.float32)


points = z_up(particles.positions)
lo, hi = points.min(0), points.max(0)
centre = (lo + hi) / 2
size = float(np.linalg.norm(hi - lo))
render_scene.add_camera(scene, (centre[0] + 0.45 * size, centre[1] - 0.85 * size, centre[2] + 0.55 * size), centre, 35)
render_scene.add_sun(scene, (40, 10, 30))


def material(name, colour, by_weights=False):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    nodes, links = m.node_tree.nodes, m.node_tree.links
    bsdf = nodes["Principled BSDF"]
    bsdf.inputs["Roughness"].default_value = 0.15
    if by_weights:
        attribute = nodes.new("ShaderNodeAttribute")
        attribute.attribute_name = "weights"
        ramp = nodes.new("ShaderNodeValToRGB")
        ramp.color_ramp.elements[0].color = (0.05, 0.15, 0.9, 1.0)
        ramp.color_ramp.elements[1].color = (0.9, 0.08, 0.05, 1.0)
        links.new(attribute.outputs["Fac"], ramp.inputs["Fac"])
        links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    else:
        bsdf.inputs["Base Color"].default_value = colour
    return m


def show(name, mesh, normals, mat, weights=None):
    data = bpy.data.meshes.new(name)
    mesh_update.write_surface(data, z_up(mesh.vertices), mesh.triangles, z_up(normals))
    if weights is not None:
        attribute = data.attributes.new("weights", "FLOAT", "POINT")
        attribute.data.foreach_set("value", np.ascontiguousarray(weights, dtype=np.float32))
    obj = bpy.data.objects.new(name, data)
    obj.data.materials.append(mat)
    scene.collection.objects.link(obj)
    return obj


grey = (0.55, 0.65, 0.8, 1.0)
for name, mesh, normals, mat, weights in [
    ("raw", raw, raw_normals, material("raw", grey), None),
    ("smoothed", smoothed, smoothed.normals, material("smoothed", grey), None),
    ("weights", raw, raw_normals, material("weights", grey, by_weights=True), meniscus.reconstruct(
        particles.positions, 0.025, cube_size=0.5, output_weights=True, **RAW).attributes["weights"]),
]:
    obj = show(name, mesh, normals, mat, weights)
    scene.render.filepath = str((out / f"{name}.png").resolve())
    bpy.ops.render.render(write_still=True)
    bpy.data.objects.remove(obj, do_unlink=True)
    print("rendered", scene.render.filepath)
