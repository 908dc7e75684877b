"""Renders the add-on's Surface From Fluid Domain beside Mantaflow's own mesh in Cycles: the baked pool of
tests/mantaflow/bake.sh opened in Blender, the add-on's surface at its defaults for the domain (narrow-band fill
included) on the left, Mantaflow's mesh of the same frame on the right, on a floor at the domain's bottom.

    blender -b --factory-startup --python-exit-code 1 --python docs/render_fluid_domain.py -- --addon-path build/addon \
        [--scene pool] [--frame 12] [--output docs/images/fluid_domain_pool.png]
"""
import pathlib
import shutil
import sys
import tempfile

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import render_scene  # noqa: E402

args = render_scene.mantaflow_figure_arguments()

meniscus, mesh_update = render_scene.library(args.addon_path)
meniscus.register()  # the add-on folder's own registration, as Blender enables it

# A copy: the .blend's '//cache' resolves next to it, and the bake stays as it was.
temporary = tempfile.TemporaryDirectory(prefix="meniscus_render_fluid_domain_")
copy = pathlib.Path(temporary.name) / args.scene
shutil.copytree(pathlib.Path(args.bakes) / f"{args.scene}_UNI", copy)
bpy.ops.wm.open_mainfile(filepath=str(copy / "scene.blend"))
domain = bpy.data.objects["Liquid Domain"]
bpy.context.view_layer.objects.active = domain
assert bpy.ops.meniscus.add_fluid_domain_surface() == {"FINISHED"}
surface = bpy.context.view_layer.objects.active
bpy.context.scene.frame_set(args.frame)
print("surface:", surface.meniscus.status)
assert not surface.meniscus.status_is_error, surface.meniscus.status
ours = surface.data.copy()  # kept when the scene is emptied below
theirs = meniscus.read_mesh(copy / "cache" / f"mesh/fluid_mesh_{args.frame:04d}.bobj.gz")

scene = render_scene.cycles_scene(args.samples, 960, 400)
water = render_scene.water_material()
mantaflow = bpy.data.meshes.new("Mantaflow")
mesh_update.write_surface(mantaflow, np.asarray(theirs.vertices, dtype=np.float32),
                          np.asarray(theirs.triangles, dtype=np.int32), theirs.normals)
for name, data, x in (("Meniscus", ours, -1.15), ("Mantaflow", mantaflow, 1.15)):
    data.materials.clear()
    data.materials.append(water)
    obj = bpy.data.objects.new(name, data)
    obj.location.x = x
    scene.collection.objects.link(obj)
bpy.ops.mesh.primitive_plane_add(size=1, location=(0, 0, -0.002))  # the domain's floor, under both
floor = bpy.context.active_object
floor.scale = (5.0, 2.4, 1.0)

render_scene.add_camera(scene, (0.0, -7.5, 2.6), (0.0, 0.0, 0.35), 50)
render_scene.add_sun(scene, (50, 0, 30))
scene.render.image_settings.color_depth = "8"
scene.render.image_settings.compression = 100
scene.render.filepath = str(pathlib.Path(args.output or f"docs/images/fluid_domain_{args.scene}.png").resolve())
bpy.ops.render.render(write_still=True)
print("rendered", scene.render.filepath)
meniscus.unregister()
