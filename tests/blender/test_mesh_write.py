"""Mesh write: mesh_update.write_surface gives the mesh it was asked for on every Blender version, whichever fast
path the version takes (uint32 index writes, topology attributes on 4.0+, edges computed in numpy, no use_smooth
write on 4.0+, custom normals as a point attribute on 4.5+).

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402


addon = _support.enable_addon()
mesh_update = _support.addon_modules(addon, "blender.mesh_update")
VERSION = tuple(bpy.app.version)


# ---- surfaces ------------------------------------------------------------------------------------------------------

def torus(major_count, minor_count, centre=(0.0, 0.0, 0.0), radii=(1.0, 0.35)):
    """Closed manifold torus: (vertices, triangles wound outward, unit normals tilted away from the geometric ones
    by a smooth field of a few degrees, so that custom normals are told apart from Blender's own)."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, major_count, endpoint=False),
                       np.linspace(0, 2 * np.pi, minor_count, endpoint=False), indexing="ij")
    u, v = u.ravel(), v.ravel()
    big, small = radii
    vertices = np.stack([(big + small * np.cos(v)) * np.cos(u), (big + small * np.cos(v)) * np.sin(u),
                         small * np.sin(v)], axis=1) + np.asarray(centre)
    normals = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], axis=1)
    normals += 0.12 * np.stack([np.sin(3 * u), np.cos(2 * v), np.sin(u + v)], axis=1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    i, j = np.meshgrid(np.arange(major_count), np.arange(minor_count), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a = i * minor_count + j
    b = ((i + 1) % major_count) * minor_count + j
    c = ((i + 1) % major_count) * minor_count + (j + 1) % minor_count
    d = i * minor_count + (j + 1) % minor_count
    triangles = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    return _outward(vertices, triangles, normals)


def open_patch(count, centre=(3.0, 0.0, 0.0)):
    """An open height field (boundary edges) with one extra triangle on an inner edge (a non-manifold edge)."""
    x, y = np.meshgrid(np.linspace(-1, 1, count), np.linspace(-1, 1, count), indexing="ij")
    x, y = x.ravel(), y.ravel()
    z = 0.2 * np.sin(2 * x) * np.cos(3 * y)
    vertices = np.stack([x, y, z], axis=1) + np.asarray(centre)
    normals = np.stack([-0.4 * np.cos(2 * x) * np.cos(3 * y), 0.6 * np.sin(2 * x) * np.sin(3 * y), np.ones_like(x)],
                       axis=1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    i, j = np.meshgrid(np.arange(count - 1), np.arange(count - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a, b, c, d = i * count + j, (i + 1) * count + j, (i + 1) * count + j + 1, i * count + j + 1
    triangles = np.concatenate([np.stack([a, b, c], axis=1), np.stack([a, c, d], axis=1)])
    # A fin on the grid's inner edge (a, c) of its first cell: three faces share that edge.
    fin_vertex = vertices[[a[0], c[0]]].mean(axis=0) + (0.0, 0.0, 0.3)
    vertices = np.vstack([vertices, fin_vertex])
    normals = np.vstack([normals, [(0.0, 0.0, 1.0)]])
    triangles = np.vstack([triangles, [(a[0], c[0], len(vertices) - 1)]])
    return vertices, triangles, normals


def _outward(vertices, triangles, normals):
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    face_normals = np.cross(b - a, c - a)
    if np.einsum("ij,ij->i", face_normals, normals[triangles].mean(axis=1)).mean() < 0:
        triangles = triangles[:, ::-1]
    return vertices, triangles, normals


def combine(*parts):
    vertices, triangles, normals, offset = [], [], [], 0
    for part_vertices, part_triangles, part_normals in parts:
        vertices.append(part_vertices)
        triangles.append(part_triangles + offset)
        normals.append(part_normals)
        offset += len(part_vertices)
    return (np.vstack(vertices).astype(np.float32), np.vstack(triangles).astype(np.int32),
            np.vstack(normals).astype(np.float32))


def attributes_for(vertices, seed):
    rng = np.random.default_rng(seed)
    return {"velocity": rng.standard_normal((len(vertices), 3)).astype(np.float32),
            "weights": rng.random(len(vertices), dtype=np.float32)}


# Two frames with different topology (the second one larger, then the first again: the arrays grow and shrink).
FRAME_A = combine(torus(120, 48))
FRAME_B = combine(torus(150, 60), open_patch(40), torus(30, 12, centre=(0.0, 0.0, 2.0)))


# ---- the scene -----------------------------------------------------------------------------------------------------

_support.clear_scene()
scene = bpy.context.scene
mesh = bpy.data.meshes.new("written")
obj = bpy.data.objects.new("written", mesh)
scene.collection.objects.link(obj)


def evaluated_mesh():
    bpy.context.view_layer.update()
    return obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data


def read_int(collection, name, count):
    values = np.empty(count, dtype=np.int32)
    collection.foreach_get(name, values)
    return values


def reference_edges(vertices, triangles):
    """Blender's own edges of the same faces (from_pydata computes them), as a sorted (E, 2) array."""
    reference = bpy.data.meshes.new("reference")
    try:
        reference.from_pydata(vertices.tolist(), [], triangles.tolist())
        edges = read_int(reference.edges, "vertices", 2 * len(reference.edges)).reshape(-1, 2)
    finally:
        bpy.data.meshes.remove(reference)
    edges.sort(axis=1)
    return edges[np.lexsort((edges[:, 1], edges[:, 0]))]


def check_written(frame, with_normals, attributes):
    """The mesh holds exactly this frame: geometry, faces, edges, smoothness, attributes, shading normals."""
    vertices, triangles, normals = frame
    # validate() first: on 3.4 reading split normals adds a loop normal layer that validate() reports.
    check(not mesh.validate(verbose=True), "mesh.validate() had something to fix")
    check(np.array_equal(mesh_update.read_vertices(mesh), vertices), "vertex positions differ")
    check(np.array_equal(mesh_update.read_triangles(mesh), triangles), "triangles differ")
    face_count = len(triangles)
    check(len(mesh.polygons) == face_count and len(mesh.loops) == 3 * face_count, "face or corner count")
    check(np.array_equal(read_int(mesh.polygons, "loop_start", face_count), np.arange(0, 3 * face_count, 3)),
          "face offsets")
    check(np.all(read_int(mesh.polygons, "loop_total", face_count) == 3), "faces are not triangles")
    smooth = np.empty(face_count, dtype=bool)
    mesh.polygons.foreach_get("use_smooth", smooth)
    check(smooth.all(), f"{np.count_nonzero(~smooth)} faces are flat")

    edges = read_int(mesh.edges, "vertices", 2 * len(mesh.edges)).reshape(-1, 2)
    corner_edges = read_int(mesh.loops, "edge_index", 3 * face_count)
    following = triangles[:, [1, 2, 0]].reshape(-1)
    joined = edges[corner_edges]
    check(np.array_equal(np.sort(joined, axis=1), np.sort(np.stack([triangles.reshape(-1), following], 1), axis=1)),
          "a corner's edge does not join its vertex to the next corner's")
    ordered = np.sort(edges, axis=1)
    ordered = ordered[np.lexsort((ordered[:, 1], ordered[:, 0]))]
    check(np.array_equal(ordered, reference_edges(vertices, triangles)), "edges differ from Blender's own")
    loose = np.empty(len(mesh.edges), dtype=bool)
    mesh.edges.foreach_get("is_loose", loose)
    check(not loose.any(), "loose edges")

    for name, values in attributes.items():
        attribute = mesh.attributes.get(name)
        check(attribute is not None, f"attribute {name} missing")
        check(attribute.domain == "POINT", f"{name} on {attribute.domain}")
        read = (mesh_update.read_point_vectors(mesh, name) if values.ndim == 2
                else mesh_update.read_point_values(mesh, name))
        check(np.array_equal(read, values), f"attribute {name} values differ")

    evaluated = evaluated_mesh()
    check((len(evaluated.vertices), len(evaluated.polygons)) == (len(vertices), face_count), "evaluated counts")
    shading = mesh_update.read_corner_normals(evaluated)
    expected = normals[triangles.reshape(-1)]
    dots = np.einsum("ij,ij->i", shading, expected)
    if with_normals:
        check(mesh.has_custom_normals, "no custom normals")
        # 3.4 and 4.1-4.4 store custom normals as 16-bit angles in each corner's normal space: ~1e-4 rad off.
        check(dots.min() > 0.9999, f"shading normals are not the custom normals (min dot {dots.min():.6f})")
    else:
        check(not mesh.has_custom_normals, "custom normals left behind")
        if mesh_update.CUSTOM_NORMALS_NEED_AUTO_SMOOTH:
            check(not mesh.use_auto_smooth, "auto smooth left on without custom normals")
        # Blender's own smooth normals: close to the tilted ones given (but at the fin's non-manifold edge), and
        # visibly not equal to them.
        check(np.median(dots) > 0.99 and dots.mean() < 0.9999,
              f"own normals: median dot {np.median(dots)}, mean {dots.mean()}")
    return dots


# ---- tests ---------------------------------------------------------------------------------------------------------

def test_fast_path_of_this_version():
    print(f"     Blender {bpy.app.version_string}, numpy {np.__version__}: topology attributes "
          f"{mesh_update.GEOMETRY_AS_ATTRIBUTES}, loop_total stored {mesh_update.POLYGON_LOOP_TOTAL_IS_STORED}, "
          f"auto smooth {mesh_update.CUSTOM_NORMALS_NEED_AUTO_SMOOTH}, "
          f"normals as point attribute {mesh_update.CUSTOM_NORMALS_AS_POINT_ATTRIBUTE}")
    check(mesh_update.GEOMETRY_AS_ATTRIBUTES == (VERSION >= (4, 0, 0)), "version switch")


def test_write_with_custom_normals():
    attributes = attributes_for(FRAME_A[0], 1)
    mesh_update.write_surface(mesh, *FRAME_A, attributes)
    dots = check_written(FRAME_A, True, attributes)
    print(f"     {len(FRAME_A[1])} triangles, min dot with the given normals {dots.min():.6f}")


def test_rewrite_with_other_topology_drops_old_attributes():
    attributes = attributes_for(FRAME_B[0], 2)
    mesh_update.write_surface(mesh, *FRAME_B, attributes)
    check_written(FRAME_B, True, attributes)
    # Back to the smaller frame with velocity only: the arrays shrink and 'weights' must not linger.
    attributes = {"velocity": attributes_for(FRAME_A[0], 3)["velocity"]}
    mesh_update.write_surface(mesh, *FRAME_A, attributes)
    check_written(FRAME_A, True, attributes)
    check(mesh.attributes.get("weights") is None, "stale 'weights' attribute")


def test_write_without_custom_normals():
    attributes = attributes_for(FRAME_B[0], 4)
    mesh_update.write_surface(mesh, FRAME_B[0], FRAME_B[1], None, attributes)
    check_written(FRAME_B, False, attributes)
    if mesh_update.CUSTOM_NORMALS_AS_POINT_ATTRIBUTE:
        check(mesh.attributes.get("custom_normal") is None, "custom_normal attribute left behind")


def test_custom_normals_come_back():
    mesh_update.write_surface(mesh, *FRAME_B, {})
    check_written(FRAME_B, True, {})


def test_inputs_in_other_dtypes_and_layouts():
    vertices, triangles, normals = FRAME_A
    # float64 positions, int64 and Fortran-ordered triangles, float64 normals: converted, same mesh.
    mesh_update.write_surface(mesh, vertices.astype(np.float64), np.asfortranarray(triangles.astype(np.int64)),
                              normals.astype(np.float64), {"velocity": attributes_for(vertices, 5)["velocity"]})
    check_written(FRAME_A, True, {"velocity": attributes_for(vertices, 5)["velocity"]})


def test_clear_and_empty_inputs():
    mesh_update.write_surface(mesh, *FRAME_A, {})
    mesh_update.clear_surface(mesh)
    check((len(mesh.vertices), len(mesh.edges), len(mesh.polygons)) == (0, 0, 0), "clear_surface left geometry")
    mesh_update.write_surface(mesh, np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int32), None, {})
    check(len(mesh.vertices) == 0 and len(evaluated_mesh().vertices) == 0, "empty input gave geometry")
    check(not mesh.validate(), "empty mesh invalid")


def _edges(triangles, vertex_count):
    return mesh_update._mesh_arrays(triangles.astype(np.int32), np.zeros((0, 4), np.int32), vertex_count)[3]


def test_edges_from_the_core_are_blenders():
    vertices, triangles, _ = FRAME_B
    edges, corner_edges = _edges(triangles, len(vertices))
    check(np.array_equal(edges, reference_edges(vertices, triangles)), "edges differ from Blender's own")
    # Corner i's edge joins its vertex and the next corner's in the same triangle.
    following = np.roll(triangles, -1, axis=1).reshape(-1)
    pairs = np.sort(np.stack([triangles.reshape(-1), following], axis=1), axis=1)
    check(np.array_equal(edges[corner_edges], pairs), "a corner's edge is not its own")
    degenerate = np.vstack([triangles, [(0, 0, 1)]]).astype(np.int32)
    check(_edges(degenerate, len(vertices)) is None, "degenerate triangle not refused")


def test_quads_and_triangles_together():
    # A unit cube: 2 faces as quads, 4 as pairs of triangles; outward winding throughout.
    vertices = np.array([(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=np.float32)
    quads = np.array([(0, 2, 3, 1), (4, 5, 7, 6)], dtype=np.int32)  # bottom (-z), top (+z)
    triangles = np.array([(0, 1, 5), (0, 5, 4), (1, 3, 7), (1, 7, 5), (3, 2, 6), (3, 6, 7), (2, 0, 4), (2, 4, 6)],
                         dtype=np.int32)
    mesh_update.write_surface(mesh, vertices, triangles, None, {}, quads)
    sizes = sorted(len(polygon.vertices) for polygon in mesh.polygons)
    check(sizes == [3] * 8 + [4] * 2, sizes)
    check(len(mesh.edges) == 12 + 4, f"{len(mesh.edges)} edges, want the cube's 12 and 4 triangle diagonals")
    check(not mesh.validate(), "validate() changed the mesh")
    corners = mesh_update.read_corner_normals(mesh)
    check(corners.shape == (8 * 3 + 2 * 4, 3), corners.shape)


def test_degenerate_triangle_falls_back_to_blender():
    vertices, triangles, _ = FRAME_A
    degenerate = np.vstack([triangles, [(0, 0, 1)]]).astype(np.int32)
    mesh_update.write_surface(mesh, vertices, degenerate, None, {})
    check(len(mesh.polygons) == len(degenerate), "faces missing")
    check(len(mesh.edges) >= len(reference_edges(vertices, triangles)), "edges missing")


_support.run(globals())
