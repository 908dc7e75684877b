"""Blender-side cost per frame of a ~1 M-triangle fluid surface: arrays -> mesh -> normals -> attributes -> depsgraph.

    blender -b --factory-startup --python-exit-code 1 --python bench/blender_mesh_update.py -- --addon-path build/addon
    build/venv/bpy-4.5/bin/python bench/blender_mesh_update.py -- --addon-path build/addon

The surface is meniscus.reconstruct of the splashsurf test set pentagonal_hexecontahedron_32286_particles.bgeo
(particle radius 0.025, cube size chosen to give ~1 M triangles; cached in build/bench/ so both Blender versions write
the same mesh). velocity (FLOAT_VECTOR) and weights (FLOAT) point attributes are synthetic (their values do not
change the cost).

Each variant runs the whole per-frame path on one reused Mesh linked to the scene; stages are timed separately:
  geometry   clear_geometry + vertices/loops/polygons add + foreach_set + update(calc_edges=True)
  attributes velocity + weights point attributes (mesh_update._write_point_attribute)
  normals    custom normals (or nothing)
  eval       view_layer.update() right after the write (the depsgraph evaluation the frame change pays)
  next eval  a following frame_set() with the mesh tagged (update_tag) but unchanged: the cost that custom normals add
             to any later evaluation
  normals read  the shading normals of the evaluated mesh, what a renderer/viewport asks for (informative)
Median of --repeat repetitions. Prints a Markdown table and a JSON line.
"""
import argparse
import json
import os
import pathlib
import statistics
import sys
import time

import bpy
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
PARTICLES = ROOT.parent / "shared" / "data" / "splashsurf" / "pentagonal_hexecontahedron_32286_particles.bgeo"  # ../shared beside the clone
VERSION = tuple(bpy.app.version)


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--addon-path", default=str(ROOT / "build" / "addon"))
    parser.add_argument("--particles", default=str(PARTICLES))
    parser.add_argument("--particle-radius", type=float, default=0.025)
    parser.add_argument("--cube-size", type=float, default=0.57,
                        help="multiple of the radius (0.4 gives 2.0 M triangles on this set, 0.57 about 1 M)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json", default="", help="also write the results to this JSON file")
    return parser.parse_args(argv)


def load_surface(arguments):
    """(vertices, triangles, normals) of the reconstructed surface, cached per cube size."""
    cache = ROOT / "build" / "bench" / f"blender_mesh_update_cs{arguments.cube_size:g}.npz"
    if cache.is_file():
        data = np.load(cache)
        return data["vertices"], data["triangles"], data["normals"]
    import meniscus

    particles = meniscus.read_particles(arguments.particles)
    mesh = meniscus.reconstruct(particles.positions, arguments.particle_radius, cube_size=arguments.cube_size)
    cache.parent.mkdir(parents=True, exist_ok=True)
    np.savez(cache, vertices=mesh.vertices, triangles=mesh.triangles, normals=mesh.normals)
    return mesh.vertices, mesh.triangles, mesh.normals


class Surface:
    """The arrays of one frame, in the layouts foreach_set reads directly."""

    def __init__(self, vertices, triangles, normals):
        self.vertex_count, self.triangle_count = len(vertices), len(triangles)
        self.vertices = np.ascontiguousarray(vertices, dtype=np.float32)
        self.triangles = np.ascontiguousarray(triangles, dtype=np.int32)
        self.normals = np.ascontiguousarray(normals, dtype=np.float32)
        self.flat_vertices = self.vertices.reshape(-1)
        self.flat_triangles = self.triangles.reshape(-1)
        self.flat_normals = self.normals.reshape(-1)
        self.corner_normals = np.ascontiguousarray(self.normals[self.triangles].reshape(-1, 3))
        rng = np.random.default_rng(1)
        self.attributes = {
            "velocity": rng.standard_normal((self.vertex_count, 3)).astype(np.float32),
            "weights": rng.random(self.vertex_count, dtype=np.float32),
        }
        # Built once, reused every frame (the 'lean' geometry path).
        self.loop_start = np.arange(0, 3 * self.triangle_count, 3, dtype=np.int32)
        self.loop_total = np.full(self.triangle_count, 3, dtype=np.int32)
        self.smooth = np.ones(self.triangle_count, dtype=bool)


# ---- geometry ------------------------------------------------------------------------------------------------------

def geometry_ours(mesh, surface):
    from meniscus.blender import mesh_update

    mesh_update.write_surface(mesh, surface.vertices, surface.triangles)


def geometry_lean(mesh, surface):
    """Pre-built loop_start/loop_total/use_smooth buffers; on 4.x positions and corner vertices written through their
    attributes; on 4.1+ no use_smooth write (faces are smooth when the 'sharp_face' attribute is absent)."""
    mesh.clear_geometry()
    mesh.vertices.add(surface.vertex_count)
    mesh.loops.add(3 * surface.triangle_count)
    mesh.polygons.add(surface.triangle_count)
    if VERSION >= (4, 0, 0):
        mesh.attributes["position"].data.foreach_set("vector", surface.flat_vertices)
        mesh.attributes[".corner_vert"].data.foreach_set("value", surface.flat_triangles)
    else:
        mesh.vertices.foreach_set("co", surface.flat_vertices)
        mesh.loops.foreach_set("vertex_index", surface.flat_triangles)
    mesh.polygons.foreach_set("loop_start", surface.loop_start)
    if VERSION < (4, 0, 0):
        mesh.polygons.foreach_set("loop_total", surface.loop_total)
    if VERSION < (4, 1, 0):
        mesh.polygons.foreach_set("use_smooth", surface.smooth)
    elif "sharp_face" in mesh.attributes:
        mesh.attributes.remove(mesh.attributes["sharp_face"])
    mesh.update(calc_edges=True)


# ---- attributes ----------------------------------------------------------------------------------------------------

def attributes_ours(mesh, surface):
    from meniscus.blender import mesh_update

    for name, values in surface.attributes.items():
        mesh_update._write_point_attribute(mesh, name, values, surface.vertex_count)


# ---- normals -------------------------------------------------------------------------------------------------------

def normals_none(mesh, surface):
    if VERSION < (4, 1, 0):
        mesh.use_auto_smooth = False


def _auto_smooth(mesh):
    if VERSION < (4, 1, 0):
        mesh.use_auto_smooth = True
        mesh.auto_smooth_angle = np.pi


def normals_from_vertices(mesh, surface):
    _auto_smooth(mesh)
    mesh.normals_split_custom_set_from_vertices(surface.normals)


def normals_per_corner(mesh, surface):
    _auto_smooth(mesh)
    mesh.normals_split_custom_set(surface.corner_normals)


def normals_attribute(mesh, surface):
    """4.5+: 'free' custom normals, a FLOAT_VECTOR attribute named custom_normal on the point domain."""
    attribute = mesh.attributes.get("custom_normal")
    if attribute is not None and (attribute.domain != "POINT" or attribute.data_type != "FLOAT_VECTOR"):
        mesh.attributes.remove(attribute)
        attribute = None
    if attribute is None:
        attribute = mesh.attributes.new("custom_normal", "FLOAT_VECTOR", "POINT")
    attribute.data.foreach_set("vector", surface.flat_normals)


# ---- the benchmark -------------------------------------------------------------------------------------------------

def variants():
    result = [
        ("anchors' way = ours: foreach_set + normals_split_custom_set_from_vertices", geometry_ours,
         normals_from_vertices),
        ("ours, no custom normals (smooth shading, Blender's vertex normals)", geometry_ours, normals_none),
        ("ours + normals_split_custom_set (per corner)", geometry_ours, normals_per_corner),
    ]
    supports_free_normals = VERSION >= (4, 5, 0)
    if supports_free_normals:
        result.append(("ours + custom_normal FLOAT_VECTOR point attribute (4.5+)", geometry_ours, normals_attribute))
    result.append(("lean geometry + normals_split_custom_set_from_vertices", geometry_lean, normals_from_vertices))
    result.append(("lean geometry, no custom normals", geometry_lean, normals_none))
    if supports_free_normals:
        result.append(("lean geometry + custom_normal point attribute (4.5+)", geometry_lean, normals_attribute))
    return result


def timed(function, *args):
    started = time.perf_counter()
    function(*args)
    return time.perf_counter() - started


def run_once(scene, obj, surface, geometry, normals, frame):
    mesh = obj.data
    stages = {}
    stages["geometry"] = timed(geometry, mesh, surface)
    stages["attributes"] = timed(attributes_ours, mesh, surface)
    stages["normals"] = timed(normals, mesh, surface)
    stages["eval"] = timed(bpy.context.view_layer.update)
    stages["total"] = stages["geometry"] + stages["attributes"] + stages["normals"] + stages["eval"]
    mesh.update_tag()
    stages["next eval"] = timed(scene.frame_set, frame + 1)
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
    from meniscus.blender import mesh_update

    started = time.perf_counter()
    shading = mesh_update.read_corner_normals(evaluated)
    stages["normals read"] = time.perf_counter() - started
    return stages, shading


def main():
    arguments = parse_arguments()
    sys.path.insert(0, os.path.abspath(arguments.addon_path))
    vertices, triangles, normals = load_surface(arguments)
    surface = Surface(vertices, triangles, normals)
    print(f"Blender {bpy.app.version_string}: {surface.vertex_count} vertices, {surface.triangle_count} triangles "
          f"(cube size {arguments.cube_size:g} x radius {arguments.particle_radius:g})")

    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 100000
    mesh = bpy.data.meshes.new("bench_surface")
    obj = bpy.data.objects.new("bench_surface", mesh)
    scene.collection.objects.link(obj)
    # One untimed warm-up (first allocations, first attribute creation).
    run_once(scene, obj, surface, geometry_ours, normals_from_vertices, 1)

    results = []
    frame = 10
    columns = ["geometry", "attributes", "normals", "eval", "total", "next eval", "normals read"]
    for name, geometry, normals_function in variants():
        runs = []
        for _ in range(arguments.repeat):
            frame += 2
            stages, shading = run_once(scene, obj, surface, geometry, normals_function, frame)
            runs.append(stages)
        medians = {column: statistics.median(run[column] for run in runs) for column in columns}
        # Check that the shading normals are the ones the core computed (or close, for Blender's own).
        agreement = float(np.mean(np.einsum("ij,ij->i", shading, surface.corner_normals)))
        smooth = bool(np.all(_read_smooth(obj.data)))
        results.append({"variant": name, "seconds": medians, "mean_dot_with_core_normals": agreement,
                        "all_faces_smooth": smooth, "triangles": len(obj.data.polygons)})
        print(f"{name}: " + ", ".join(f"{c} {medians[c]:.3f}" for c in columns) +
              f"; mean dot {agreement:.4f}; smooth {smooth}")
        sys.stdout.flush()

    print()
    print(f"| Blender {bpy.app.version_string} | " + " | ".join(columns) + " | mean n·n_core |")
    print("|---|" + "---:|" * (len(columns) + 1))
    for result in results:
        print(f"| {result['variant']} | " + " | ".join(f"{result['seconds'][c]:.3f}" for c in columns) +
              f" | {result['mean_dot_with_core_normals']:.4f} |")
    record = {"blender": bpy.app.version_string, "vertices": surface.vertex_count,
              "triangles": surface.triangle_count, "repeat": arguments.repeat, "results": results}
    print("JSON " + json.dumps(record))
    if arguments.json:
        pathlib.Path(arguments.json).parent.mkdir(parents=True, exist_ok=True)
        pathlib.Path(arguments.json).write_text(json.dumps(record, indent=1))


def _read_smooth(mesh):
    smooth = np.empty(len(mesh.polygons), dtype=bool)
    mesh.polygons.foreach_get("use_smooth", smooth)
    return smooth


main()
