"""Renders without the add-on: a baked surface exported as an Alembic mesh sequence through Blender's own exporter
plays through a Mesh Sequence Cache modifier, and a Blender process without Meniscus shows the same frames (vertex
and face counts of the baked meshes, the velocity attribute for motion blur, smooth normals) from the saved .blend.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import subprocess
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
cache = addon.cache
native_cache = _support.addon_modules(addon, "blender.native_cache")
FRAMES = (29, 30, 31)
# Blender keeps the Alembic archive open while the scene uses it (freeing the CacheFile does not close it), and
# Windows deletes no open file: there the archive stays in the temporary folder.
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_native_", ignore_cleanup_errors=True)
_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()
settings = surface.meniscus
settings.is_surface = False
settings.cube_size = settings.render_cube_size = 1.5
settings.smoothing_iterations = 2
settings.smoothing_reach = 0.0
settings.cache_pattern = os.path.join(_temporary.name, "cache", "fluid_####.npz")
settings.is_surface = True
baked = {}


def evaluated_counts(obj):
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.data
    return len(mesh.vertices), len(mesh.polygons)


def test_export_plays_the_baked_frames_through_the_modifier():
    if not native_cache.can_export():  # e.g. Debian's 3.4: the export refuses, saying why
        try:
            native_cache.export_alembic(surface, scene, FRAMES[0], FRAMES[-1])
        except native_cache.NativeCacheError as error:
            check("without Alembic" in str(error) and not settings.use_native_cache, str(error))
            return
        raise AssertionError("an export without Alembic did not refuse")
    result = bpy.ops.meniscus.bake(object_name=surface.name, use_surface_range=False, frame_start=FRAMES[0],
                                   frame_end=FRAMES[-1])
    check(result == {"FINISHED"}, result)
    for frame in FRAMES:
        mesh = cache.load_mesh(settings.cache_pattern.replace("####", f"{frame:04d}"))
        baked[frame] = (len(mesh.vertices), len(mesh.triangles))
    check(len(set(baked.values())) == len(FRAMES), f"the frames should differ: {baked}")
    path = native_cache.export_alembic(surface, scene, FRAMES[0], FRAMES[-1],
                                       os.path.join(_temporary.name, "fluid.abc")).path
    check(os.path.getsize(path) > 10000 and settings.use_native_cache, path)
    check([m.type for m in surface.modifiers] == ["MESH_SEQUENCE_CACHE"], list(surface.modifiers))
    for frame in (30, 29, 31):
        scene.frame_set(frame)
        check(evaluated_counts(surface) == baked[frame], f"frame {frame}: {evaluated_counts(surface)} != {baked[frame]}")


_CHILD = """
import bpy, numpy, sys
if not bpy.app.binary_path:
    bpy.ops.wm.read_factory_settings(use_empty=True)  # the module has no --factory-startup: no add-ons either
    bpy.ops.wm.open_mainfile(filepath=sys.argv[-1])
print("MENISCUS_LOADED", hasattr(bpy.types.Object, "meniscus"))
obj = bpy.data.objects[{name!r}]
for frame in {frames!r}:
    bpy.context.scene.frame_set(frame)
    mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
    velocity = mesh.attributes.get("velocity")
    values = numpy.zeros(3 * len(mesh.vertices), dtype=numpy.float32)
    if velocity is not None:
        velocity.data.foreach_get("vector", values)
    moving = bool(numpy.abs(values).max() > 0.01)  # the fluid moves at these frames (m/s)
    print("FRAME", frame, len(mesh.vertices), len(mesh.polygons), moving)
    print("ATTRIBUTES", frame, sorted(mesh.attributes.keys()), float(numpy.abs(values).max()))
sys.stdout.flush()
"""


def test_a_blender_without_meniscus_renders_the_same_frames():
    if not baked:  # no Alembic in this Blender (checked above): a farm without Meniscus gets no native cache from it
        check(not native_cache.can_export(), "the export test did not run")
        return
    blend = os.path.join(_temporary.name, "farm.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True)
    code = _CHILD.format(name=surface.name, frames=FRAMES)
    if _support.AS_MODULE:
        command = [sys.executable, "-c", code + "import os; os._exit(0)\n", blend]
    else:
        command = [bpy.app.binary_path, "-b", "--factory-startup", blend, "--python-expr", code]
    completed = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=180)
    output = completed.stdout
    check("MENISCUS_LOADED False" in output, f"the add-on was loaded:\n{output[-3000:]}")
    shown = {int(f): ((int(v), int(p)), moving == "True") for _, f, v, p, moving in
             (line.split() for line in output.splitlines() if line.startswith("FRAME "))}
    check({frame: counts for frame, (counts, _) in shown.items()} == baked, f"without the add-on: {shown}, baked {baked}")
    check(all(moving for _, moving in shown.values()), f"no velocity for motion blur: {shown}\n{output[-1500:]}")


def _cleanup():
    _temporary.cleanup()
    addon.unregister()


_support.run(globals(), cleanup=_cleanup)
