"""Writes reconstructed surfaces into a Blender Mesh: the one place that knows Blender version differences.

The per-frame path reuses one Mesh and fills it with `foreach_set` from contiguous numpy buffers, which is several
times faster than `from_pydata` and skips `validate()` (the core's meshes are consistent by construction).

Version differences handled here:
- Blender < 4.0: `MeshPolygon.loop_total` is stored and starts at 0 after `polygons.add`, so it must be written;
  from 4.0 it is derived from the offsets (`loop_start`) and read-only.
- Blender < 4.1: custom normals only take effect with `Mesh.use_auto_smooth`; 4.1 removed that property and
  custom normals work on their own.
"""
import bpy
import numpy as np

BLENDER_VERSION = tuple(bpy.app.version)
POLYGON_LOOP_TOTAL_IS_STORED = BLENDER_VERSION < (4, 0, 0)
CUSTOM_NORMALS_NEED_AUTO_SMOOTH = BLENDER_VERSION < (4, 1, 0)
# 4.5 stores free custom normals as a FLOAT_VECTOR attribute named "custom_normal": on the point domain it is
# written with one foreach_set (0.002 s for 1 M triangles, against 1.5 s for normals_split_custom_set_from_vertices;
# bench/results/blender_mesh_update.md).
CUSTOM_NORMALS_AS_POINT_ATTRIBUTE = BLENDER_VERSION >= (4, 5, 0)

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


def clear_surface(mesh):
    """Leaves the mesh empty (no vertices), keeping its materials and settings."""
    mesh.clear_geometry()
    mesh.update()


def write_surface(mesh, vertices, triangles, normals=None, point_attributes=None):
    """Replaces the mesh's geometry by a triangle mesh; returns {attribute name: name stored under} for attributes
    stored under another name (see RESERVED_NAMES) or not at all (None: a shape Blender has no type for).

    vertices (V, 3) and triangles (F, 3) index arrays; normals (V, 3) unit vectors used as custom normals when
    given; point_attributes maps names to (V,) float arrays (FLOAT point attributes, e.g. 'weights'), (V,) integer
    arrays (INT, e.g. particle ids carried from the nearest particle) or (V, 3) float arrays (FLOAT_VECTOR, e.g.
    'velocity'). clear_geometry() drops the attributes of the previous frame, so an attribute that is no longer
    produced does not linger with stale values.
    """
    vertex_count = len(vertices)
    triangle_count = len(triangles)
    mesh.clear_geometry()
    if vertex_count == 0 or triangle_count == 0:
        mesh.update()
        return {}

    mesh.vertices.add(vertex_count)
    mesh.vertices.foreach_set("co", _flat(vertices, np.float32))
    mesh.loops.add(3 * triangle_count)
    mesh.loops.foreach_set("vertex_index", _flat(triangles, np.int32))
    mesh.polygons.add(triangle_count)
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * triangle_count, 3, dtype=np.int32))
    if POLYGON_LOOP_TOTAL_IS_STORED:
        mesh.polygons.foreach_set("loop_total", np.full(triangle_count, 3, dtype=np.int32))
    # A fluid surface has no hard edges: every face smooth, so shading interpolates the vertex normals.
    mesh.polygons.foreach_set("use_smooth", np.ones(triangle_count, dtype=bool))
    mesh.update(calc_edges=True)

    stored_elsewhere = {}
    for name, values in (point_attributes or {}).items():
        stored = _write_point_attribute(mesh, name, values, vertex_count)
        if stored != name:
            stored_elsewhere[name] = stored

    if normals is not None and len(normals) == vertex_count and CUSTOM_NORMALS_AS_POINT_ATTRIBUTE:
        attribute = mesh.attributes.get("custom_normal")
        if attribute is not None and (attribute.domain != "POINT" or attribute.data_type != "FLOAT_VECTOR"):
            mesh.attributes.remove(attribute)
            attribute = None
        if attribute is None:
            attribute = mesh.attributes.new("custom_normal", "FLOAT_VECTOR", "POINT")
        attribute.data.foreach_set("vector", _flat(normals, np.float32))
    elif normals is not None and len(normals) == vertex_count:
        if CUSTOM_NORMALS_NEED_AUTO_SMOOTH:
            mesh.use_auto_smooth = True
            # Auto smooth also splits normals at edges sharper than this angle; custom normals should win everywhere.
            mesh.auto_smooth_angle = np.pi
        mesh.normals_split_custom_set_from_vertices(np.ascontiguousarray(normals, dtype=np.float32))
    elif CUSTOM_NORMALS_NEED_AUTO_SMOOTH:
        # Without custom normals, auto smooth would only add splits at sharp angles: plain smooth shading is wanted.
        mesh.use_auto_smooth = False
    return stored_elsewhere


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
