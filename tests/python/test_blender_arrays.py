"""The mesh in Blender's layout, made by the core (api.blender_mesh_arrays): corners, face offsets, edges and each
corner's edge, equal to a plain numpy construction of the same arrays, the same at any thread count."""
import numpy as np
import pytest

import meniscus
from meniscus import api

BUNNY = "splashsurf/bunny_frame_14_7705_particles.vtk"


def reference(triangles, quads, vertex_count):
    """The arrays as numpy builds them: corners in face order, each corner's edge to the next corner of its face,
    distinct (low, high) pairs in ascending order."""
    faces = [np.asarray(triangles, np.int64).reshape(-1, 3), np.asarray(quads, np.int64).reshape(-1, 4)]
    corners = np.concatenate([f.reshape(-1) for f in faces])
    following = np.concatenate([np.roll(f, -1, axis=1).reshape(-1) for f in faces])
    offsets = np.concatenate([np.arange(0, 3 * len(faces[0]), 3), 3 * len(faces[0]) + np.arange(0, 4 * len(faces[1]), 4)])
    keys = np.minimum(corners, following) * vertex_count + np.maximum(corners, following)
    unique, corner_edges = np.unique(keys, return_inverse=True)
    edges = np.stack([unique // vertex_count, unique % vertex_count], axis=1)
    return corners, offsets, edges, corner_edges


def check_equal(arrays, triangles, quads, vertex_count):
    corners, offsets, edges, corner_edges = reference(triangles, quads, vertex_count)
    assert arrays["corner_vertices"].dtype == np.int32 and arrays["edges"].dtype == np.int32
    assert np.array_equal(arrays["corner_vertices"], corners)
    assert np.array_equal(arrays["face_offsets"], offsets)
    assert np.array_equal(arrays["edges"], edges)
    assert np.array_equal(arrays["corner_edges"], corner_edges.reshape(-1))


def test_a_cube_of_quads_and_triangles():
    quads = np.array([(0, 2, 3, 1), (4, 5, 7, 6)], dtype=np.int32)
    triangles = np.array([(0, 1, 5), (0, 5, 4), (1, 3, 7), (1, 7, 5), (3, 2, 6), (3, 6, 7), (2, 0, 4), (2, 4, 6)],
                         dtype=np.int32)
    arrays = api.blender_mesh_arrays(triangles, quads, 8)
    assert len(arrays["edges"]) == 12 + 4  # the cube's edges and the triangle pairs' diagonals
    check_equal(arrays, triangles, quads, 8)


def test_a_reconstructed_surface_at_any_thread_count(shared):
    particles = meniscus.read_particles(shared / BUNNY)
    mesh = meniscus.reconstruct(particles.positions, 0.025, cube_size=1.0, smoothing_iterations=0)
    one = api.blender_mesh_arrays(mesh.triangles, None, len(mesh.vertices), threads=1)
    check_equal(one, mesh.triangles, np.zeros((0, 4), np.int32), len(mesh.vertices))
    two = api.blender_mesh_arrays(mesh.triangles, None, len(mesh.vertices), threads=2)
    assert all(np.array_equal(one[name], two[name]) for name in one)


def test_a_face_repeating_a_vertex_leaves_the_edges_to_blender():
    arrays = api.blender_mesh_arrays(np.array([(0, 1, 2), (0, 0, 1)], np.int32), None, 3)
    assert arrays["edges"] is None and arrays["corner_edges"] is None
    assert list(arrays["corner_vertices"]) == [0, 1, 2, 0, 0, 1] and list(arrays["face_offsets"]) == [0, 3]


def test_an_index_outside_the_vertices_is_refused():
    with pytest.raises(ValueError, match="refer to no vertex"):
        api.blender_mesh_arrays(np.array([(0, 1, 5)], np.int32), None, 3)


def test_without_quads_the_corners_are_a_view_of_the_triangles():
    triangles = np.array([(0, 1, 2), (2, 1, 3)], np.int32)
    arrays = api.blender_mesh_arrays(triangles, None, 4)
    assert np.shares_memory(arrays["corner_vertices"], triangles)
    check_equal(arrays, triangles, np.zeros((0, 4), np.int32), 4)
    # Vertices no corner uses leave empty groups in the edge sort (the last one past the end of its keys).
    check_equal(api.blender_mesh_arrays(triangles, None, 9), triangles, np.zeros((0, 4), np.int32), 9)
    empty = api.blender_mesh_arrays(np.zeros((0, 3), np.int32), None, 5)
    assert len(empty["corner_vertices"]) == 0 and len(empty["edges"]) == 0 and len(empty["face_offsets"]) == 0


@pytest.mark.parametrize("argument", ["triangles", "quads"])
def test_index_arrays_that_are_not_numpy_arrays_are_refused_by_name(argument):
    """The core's own function (api converts lists first): a list is refused with a message, not read as an array."""
    faces = {"triangles": np.array([(0, 1, 2)], np.int32), "quads": np.array([(0, 1, 2, 3)], np.int32)}
    faces[argument] = faces[argument].tolist()
    with pytest.raises(ValueError, match=f"{argument} must be a C-contiguous int32 array of shape .*got list"):
        meniscus._core.blender_mesh_arrays(faces["triangles"], faces["quads"], 4, 1)
    if argument == "triangles":  # write_mesh's triangles are typed as an array: pybind11 refuses a list itself
        return
    with pytest.raises(ValueError, match="quads must be a C-contiguous int32 array"):
        meniscus._core.write_mesh("unused.ply", np.zeros((4, 3), np.float32), faces["triangles"], None, {},
                                  faces["quads"])
