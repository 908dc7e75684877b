"""Writes reconstructed surfaces into a Blender Mesh: the one place that knows Blender version differences.

The per-frame path reuses one Mesh and fills it with `foreach_set` from contiguous numpy buffers, which is several
times faster than `from_pydata` and skips `validate()` (the core's meshes are consistent by construction).
bench/blender_mesh_write_profile.py times every step below on each Blender version
(bench/results/blender_mesh_write_profile.md); for 1 M triangles on this project's 2-core machine:

- foreach_set only copies a buffer in one go when its item type matches the RNA property exactly, unsigned
  included: `vertex_index`, `loop_start`, `loop_total`, edge `vertices` and `edge_index` are unsigned, so they are
  written from uint32 views (int32 falls back to a per-item conversion: 0.13-0.27 s for the corners alone).
- From 4.0, positions, corner vertices, edge vertices and corner edges are generic attributes (`position`,
  `.corner_vert`, `.edge_verts`, `.corner_edge`) written directly, without the per-item MeshVertex/MeshLoop access.
- Corners, face starts and edges come from the core (api.blender_mesh_arrays: a counting sort of the corners'
  vertex pairs in C++, 0.03-0.07 s on the busy machine; the numpy sort it replaces took 0.06-0.2 s and its corner
  arrays more) and are written with the corners' edge indices, instead of `Mesh.update(calc_edges=True)`,
  Blender's hash maps (0.4-0.75 s).
- From 4.0 faces are smooth when the `sharp_face` attribute is absent, as it is after `clear_geometry`, so
  `use_smooth` is not written (on 5.x that write alone costs 0.1-0.17 s).

Version differences handled here:
- Blender < 4.0: `MeshPolygon.loop_total` is stored and starts at 0 after `polygons.add`, so it must be written;
  from 4.0 it is derived from the offsets (`loop_start`) and read-only.
- Blender < 4.1: custom normals only take effect with `Mesh.use_auto_smooth`; 4.1 removed that property and
  custom normals work on their own.
- Blender < 4.5: custom normals can only be set through `normals_split_custom_set_from_vertices`, which encodes them
  in every corner's normal space (0.8-1.0 s; per corner, `normals_split_custom_set`, is slower still), and on 3.4
  auto smooth recomputes split normals at every depsgraph evaluation (0.6-0.7 s). The add-on's "Custom Normals" off
  avoids both; Blender's own vertex normals then differ from the core's by 1.4 degrees (median, 4.2 at the 99th
  percentile).
"""
import bpy
import numpy as np

from .. import api

BLENDER_VERSION = tuple(bpy.app.version)
POLYGON_LOOP_TOTAL_IS_STORED = BLENDER_VERSION < (4, 0, 0)
CUSTOM_NORMALS_NEED_AUTO_SMOOTH = BLENDER_VERSION < (4, 1, 0)
# 4.5 stores free custom normals as a FLOAT_VECTOR attribute named "custom_normal": on the point domain it is
# written with one foreach_set (0.002 s for 1 M triangles, against 1.5 s for normals_split_custom_set_from_vertices;
# bench/results/blender_mesh_update.md).
CUSTOM_NORMALS_AS_POINT_ATTRIBUTE = BLENDER_VERSION >= (4, 5, 0)
# 4.0 stores the mesh's topology as generic attributes and face smoothness as the absence of `sharp_face`.
GEOMETRY_AS_ATTRIBUTES = BLENDER_VERSION >= (4, 0, 0)

VELOCITY_ATTRIBUTE = "velocity"  # the name Cycles reads for motion blur of meshes whose topology changes
# Names with a meaning of their own in some Blender version: built-in mesh layers ('position', 'sharp_face', ...),
# geometry-node fields ('id' is an integer stable ID in 4.x, 'normal' a read-only field) and our own custom normals.
# Blender versions disagree on which of them attributes.new() refuses (4.5 refuses 'id', 5.0 accepts it), so the
# rule does not depend on the version: a particle attribute of such a name is stored with this prefix
# ('id' -> 'particle_id') in every version, and write_surface reports it.
RESERVED_NAME_PREFIX = "particle_"
RESERVED_NAMES = frozenset({
    "position", "normal", "id", "material_index", "sharp_face", "sharp_edge", "crease_vert", "crease_edge",
    "bevel_weight_vert", "bevel_weight_edge", "custom_normal", "UVMap", "velocity_blur",
})


def _flat(array, dtype):
    # foreach_set reads the buffer directly when dtype and layout match the RNA property; anything else would make
    # it fall back to a slow element-by-element conversion.
    return np.ascontiguousarray(array, dtype=dtype).reshape(-1)


def _unsigned(indices):
    """uint32 view of non-negative int32 indices (a copy only when they are not contiguous int32)."""
    return _flat(indices, np.int32).view(np.uint32)


def clear_surface(mesh):
    """Leaves the mesh empty (no vertices), keeping its materials and settings."""
    mesh.clear_geometry()
    mesh.update()


class SurfaceWrite:
    """A surface as the buffers write_surface copies into a mesh: positions, corners, face starts, edges and custom
    normals in the types foreach_set and Blender's functions take. The core makes the corners, faces and edges;
    no bpy: a background thread can build it (playback's worker does), leaving Blender's thread only the copies.

    vertices (V, 3), triangles (F, 3) and quads (Q, 4, optional: the core's --generate-quads) index arrays; normals
    (V, 3) unit vectors used as custom normals when given.
    """

    def __init__(self, vertices, triangles, normals=None, quads=None):
        self.vertex_count = len(vertices)
        triangles = np.ascontiguousarray(triangles, dtype=np.int32).reshape(-1, 3)
        quads = np.zeros((0, 4), dtype=np.int32) if quads is None else \
            np.ascontiguousarray(quads, dtype=np.int32).reshape(-1, 4)
        self.is_empty = self.vertex_count == 0 or len(triangles) + len(quads) == 0
        if self.is_empty:
            return
        self.positions = _flat(vertices, np.float32)
        self.corners, self.face_starts, self.face_totals, self.edges = _mesh_arrays(triangles, quads, self.vertex_count)
        self.normals = None
        if normals is not None and len(normals) == self.vertex_count:
            self.normals = _normals_argument(normals)


def write_surface(mesh, vertices, triangles, normals=None, point_attributes=None, quads=None, prepared=None):
    """Replaces the mesh's geometry by a triangle (and quad) mesh; returns {attribute name: name stored under} for
    attributes stored under another name (see RESERVED_NAMES) or not at all (None: a shape Blender has no type for).

    The geometry is that of SurfaceWrite(vertices, triangles, normals, quads), or prepared when given (already built
    from them, e.g. by a background thread). point_attributes maps names to (V,) float arrays (FLOAT point
    attributes, e.g. 'weights'), (V,) integer arrays (INT, e.g. particle ids carried from the nearest particle) or
    (V, 3) float arrays (FLOAT_VECTOR, e.g. 'velocity'). clear_geometry() drops the attributes of the previous frame,
    so an attribute that is no longer produced does not linger with stale values.
    """
    surface = prepared if prepared is not None else SurfaceWrite(vertices, triangles, normals, quads)
    mesh.clear_geometry()
    if surface.is_empty:
        mesh.update()
        return {}

    _write_vertices(mesh, surface.positions)
    _write_faces(mesh, surface.corners, surface.face_starts, surface.face_totals)
    if surface.edges is None:
        mesh.update(calc_edges=True)  # degenerate triangles: let Blender decide what their edges are
    else:
        _write_edges(mesh, *surface.edges)
        mesh.update()  # the edges exist: no calc_edges

    stored_elsewhere = {}
    for name, values in (point_attributes or {}).items():
        stored = _write_point_attribute(mesh, name, values, surface.vertex_count)
        if stored != name:
            stored_elsewhere[name] = stored

    if surface.normals is not None:
        _write_custom_normals(mesh, surface.normals)
    elif CUSTOM_NORMALS_NEED_AUTO_SMOOTH:
        # Without custom normals, auto smooth would only add splits at sharp angles: plain smooth shading is wanted.
        mesh.use_auto_smooth = False
    return stored_elsewhere


def _write_vertices(mesh, positions):
    mesh.vertices.add(len(positions) // 3)
    if GEOMETRY_AS_ATTRIBUTES:
        mesh.attributes["position"].data.foreach_set("vector", positions)
    else:
        mesh.vertices.foreach_set("co", positions)


def _mesh_arrays(triangles, quads, vertex_count):
    """(corners, face starts as uint32, face totals or None where Blender derives them, (edges, corner edges) or None
    when a face repeats a vertex) of triangles then quads, made by the core (api.blender_mesh_arrays: a counting sort
    of the corners' vertex pairs, Python's lock released)."""
    arrays = api.blender_mesh_arrays(triangles, quads, vertex_count)
    starts = arrays["face_offsets"].view(np.uint32)
    totals = None
    if POLYGON_LOOP_TOTAL_IS_STORED:
        totals = np.full(len(starts), 3, dtype=np.uint32)
        totals[len(triangles):] = 4
    edges = None if arrays["edges"] is None else (arrays["edges"], arrays["corner_edges"])
    # Without quads the corners are a view of the triangles' indices (no copy made, none kept in the frame cache).
    corners = arrays["corner_vertices"]
    return corners, starts, totals, edges


def _write_faces(mesh, corners, starts, totals):
    """Corners (loops) and faces (polygons), every face smooth."""
    face_count = len(starts)
    mesh.loops.add(len(corners))
    if GEOMETRY_AS_ATTRIBUTES:
        mesh.attributes[".corner_vert"].data.foreach_set("value", corners)
    else:
        mesh.loops.foreach_set("vertex_index", _unsigned(corners))
    mesh.polygons.add(face_count)
    mesh.polygons.foreach_set("loop_start", starts)
    if totals is not None:
        mesh.polygons.foreach_set("loop_total", totals)
    # A fluid surface has no hard edges: every face smooth, so shading interpolates the vertex normals.
    if GEOMETRY_AS_ATTRIBUTES:
        sharp_face = mesh.attributes.get("sharp_face")  # absent after clear_geometry: all faces smooth
        if sharp_face is not None:
            mesh.attributes.remove(sharp_face)
    else:
        mesh.polygons.foreach_set("use_smooth", np.ones(face_count, dtype=bool))


def _write_edges(mesh, edges, corner_edges):
    mesh.edges.add(len(edges))
    if GEOMETRY_AS_ATTRIBUTES:
        mesh.attributes[".edge_verts"].data.foreach_set("value", edges.reshape(-1))
        mesh.attributes[".corner_edge"].data.foreach_set("value", corner_edges)
    else:
        mesh.edges.foreach_set("vertices", _unsigned(edges))
        mesh.loops.foreach_set("edge_index", _unsigned(corner_edges))


def _normals_argument(normals):
    """Custom normals as this Blender's write takes them: a flat float32 buffer for foreach_set (4.5+), (V, 3)
    float32 for normals_split_custom_set_from_vertices."""
    if CUSTOM_NORMALS_AS_POINT_ATTRIBUTE:
        return _flat(normals, np.float32)
    return np.ascontiguousarray(normals, dtype=np.float32).reshape(-1, 3)


def _write_custom_normals(mesh, normals):
    """normals: as _normals_argument gives them."""
    if CUSTOM_NORMALS_AS_POINT_ATTRIBUTE:
        attribute = mesh.attributes.get("custom_normal")
        if attribute is not None and (attribute.domain != "POINT" or attribute.data_type != "FLOAT_VECTOR"):
            mesh.attributes.remove(attribute)
            attribute = None
        if attribute is None:
            attribute = mesh.attributes.new("custom_normal", "FLOAT_VECTOR", "POINT")
        attribute.data.foreach_set("vector", normals)
        return
    if CUSTOM_NORMALS_NEED_AUTO_SMOOTH:
        mesh.use_auto_smooth = True
        # Auto smooth also splits normals at edges sharper than this angle; custom normals should win everywhere.
        mesh.auto_smooth_angle = np.pi
    # A numpy array, although the function parses a list of [x, y, z] lists faster (3.4, 10 k vertices: 9 against
    # 13 ms): converting on this thread costs that gain back (measured: 0.077 against 0.066 s a 39 k-triangle frame),
    # and a list prepared by the worker holds 5-6 times the array's memory, unseen by the playback cache's budget.
    mesh.normals_split_custom_set_from_vertices(normals)


# Attribute layout by value kind and width: (data type, the RNA property foreach_set writes, buffer dtype).
_ATTRIBUTE_KINDS = {
    ("f", 1): ("FLOAT", "value", np.float32),
    ("f", 3): ("FLOAT_VECTOR", "vector", np.float32),
    ("i", 1): ("INT", "value", np.int32),
}


def stored_attribute_name(name):
    """The name a particle attribute gets on the mesh: its own, or prefixed when Blender gives it a meaning."""
    return RESERVED_NAME_PREFIX + name if name in RESERVED_NAMES or name.startswith(".") else name


def _write_point_attribute(mesh, name, values, vertex_count):
    """Writes one point attribute; returns the name it was stored under, or None when it could not be stored."""
    values = np.asarray(values)
    if len(values) != vertex_count:
        return None
    width = 1 if values.ndim == 1 else int(np.prod(values.shape[1:]))
    kind = _ATTRIBUTE_KINDS.get(("i" if values.dtype.kind in "iub" else "f", width))
    if kind is None and values.dtype.kind in "iub":  # whole-number vectors: as float vectors
        kind = _ATTRIBUTE_KINDS.get(("f", width))
    if kind is None:
        return None
    data_type, rna_property, dtype = kind
    stored = stored_attribute_name(name)
    attribute = mesh.attributes.get(stored)
    if attribute is not None and (attribute.domain != "POINT" or attribute.data_type != data_type):
        mesh.attributes.remove(attribute)
        attribute = None
    if attribute is None:
        attribute = mesh.attributes.new(name=stored, type=data_type, domain="POINT")
    if attribute is None:  # a name this Blender refuses that the list above does not know yet
        return None
    attribute.data.foreach_set(rna_property, _flat(values, dtype))
    return stored


def read_vertices(mesh):
    """(V, 3) float32 vertex positions, for tests and diagnostics."""
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def read_triangles(mesh):
    """(F, 3) int32 vertex indices of a triangle mesh."""
    indices = np.empty(len(mesh.loops), dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", indices)
    return indices.reshape(-1, 3)


def read_corner_normals(mesh):
    """(3F, 3) float32 shading normals per face corner, which include custom normals, in any Blender version."""
    normals = np.empty(len(mesh.loops) * 3, dtype=np.float32)
    if hasattr(mesh, "corner_normals"):  # 4.1+: always up to date
        mesh.corner_normals.foreach_get("vector", normals)
    else:
        mesh.calc_normals_split()
        mesh.loops.foreach_get("normal", normals)
    return normals.reshape(-1, 3)


def read_point_values(mesh, name):
    """(V,) values of a FLOAT (float32) or INT (int32) point attribute, or None when the mesh has no such attribute."""
    attribute = mesh.attributes.get(name)
    if attribute is None:
        return None
    values = np.empty(len(mesh.vertices), dtype=np.int32 if attribute.data_type == "INT" else np.float32)
    attribute.data.foreach_get("value", values)
    return values


def read_point_vectors(mesh, name):
    """(V, 3) float32 values of a FLOAT_VECTOR point attribute, or None when the mesh has no such attribute."""
    attribute = mesh.attributes.get(name)
    if attribute is None:
        return None
    values = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    attribute.data.foreach_get("vector", values)
    return values.reshape(-1, 3)
