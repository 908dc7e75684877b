"""The Python API: numpy in and out, zero-copy input, clear errors, no bpy needed."""
import os
import pathlib
import subprocess
import sys
import threading
import time
import tracemalloc

import numpy as np
import pytest

import meniscus

BUNNY = "splashsurf/bunny_frame_14_7705_particles.vtk"


def test_api_never_imports_bpy(tmp_path):
    # A `bpy` that fails on import, first on the path: any import of it by the package would break this run.
    (tmp_path / "bpy").mkdir()
    (tmp_path / "bpy" / "__init__.py").write_text("raise ImportError('the bpy-free package imported bpy')\n")
    code = ("import numpy, meniscus, meniscus.cache, meniscus.sequence, meniscus.parameters, meniscus.cli; "
            "mesh = meniscus.reconstruct(numpy.zeros((1, 3), numpy.float32), 0.025); "
            "assert len(mesh.triangles) > 0; print('ok')")
    package = pathlib.Path(meniscus.__file__).resolve().parents[1]
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            env={**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), str(package)])})
    assert result.returncode == 0 and result.stdout.strip() == "ok", result.stderr


def test_bunny_reconstruction_gives_numpy_arrays(shared):
    particles = meniscus.read_particles(shared / BUNNY)
    assert particles.positions.shape == (7706, 3) and particles.positions.dtype == np.float32
    assert particles.attributes["velocity"].shape == (7706, 3)
    mesh = meniscus.reconstruct(particles.positions, 0.025, cube_size=1.0,
                                attributes={"velocity": particles.attributes["velocity"]})
    assert mesh.vertices.dtype == np.float32 and mesh.vertices.shape[1] == 3
    assert mesh.triangles.dtype == np.int32 and mesh.triangles.shape[1] == 3
    assert 35000 <= len(mesh.triangles) <= 40000
    assert mesh.normals.shape == mesh.vertices.shape
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-4)
    assert mesh.attributes["velocity"].shape == mesh.vertices.shape
    assert np.isfinite(mesh.attributes["velocity"]).all()
    assert meniscus.check_mesh(mesh)["ok"]
    assert mesh.stats["counts"]["particles"] == 7706
    assert "level set and marching cubes" in mesh.stats["seconds"]


def test_float64_and_float32_positions_agree(shared):
    positions = meniscus.read_particles(shared / BUNNY).positions
    a = meniscus.reconstruct(positions, 0.025, cube_size=1.0)
    b = meniscus.reconstruct(positions.astype(np.float64), 0.025, cube_size=1.0)
    np.testing.assert_array_equal(a.triangles, b.triangles)
    np.testing.assert_array_equal(a.vertices, b.vertices)


@pytest.mark.parametrize("bad, message", [
    (np.zeros((10, 3), dtype=np.int32), "float32 or float64"),
    (np.zeros((10, 2), dtype=np.float32), "shape (N, 3)"),
    (np.zeros((3, 10), dtype=np.float32)[:, :3], "C-contiguous"),
])
def test_wrong_positions_raise_value_error_naming_them(bad, message):
    with pytest.raises(ValueError, match="positions") as error:
        meniscus.reconstruct(bad, 0.025)
    assert message in str(error.value)


@pytest.mark.parametrize("name, value", [("particle_radius", 0.0), ("cube_size", -1.0), ("smoothing_length", float("nan")),
                                         ("iso_threshold", 0.0)])
def test_bad_parameters_raise_value_error_naming_them(name, value):
    kwargs = {"particle_radius": 0.025, name: value}
    with pytest.raises(ValueError, match=name):
        meniscus.reconstruct(np.zeros((1, 3), dtype=np.float32), **kwargs)


def test_nan_positions_are_counted_or_skipped():
    positions = np.array([[0, 0, 0], [np.nan, 0, 0], [0.01, 0, 0]], dtype=np.float32)
    with pytest.raises(ValueError, match="1 of 3 particles have NaN"):
        meniscus.reconstruct(positions, 0.025)
    mesh = meniscus.reconstruct(positions, 0.025, skip_invalid=True)
    assert len(mesh.triangles) > 0
    assert any("NaN" in w for w in mesh.stats["warnings"])


def test_empty_input_gives_empty_mesh_and_warning():
    mesh = meniscus.reconstruct(np.zeros((0, 3), dtype=np.float32), 0.025)
    assert mesh.vertices.shape == (0, 3) and mesh.triangles.shape == (0, 3)
    assert mesh.stats["warnings"]


def test_memory_refusal_gives_memory_error_with_estimate():
    with pytest.raises(MemoryError, match="would need about"):
        meniscus.reconstruct(np.zeros((1, 3), dtype=np.float32), 0.025, cube_size=1e-4)


def test_attribute_shape_is_checked():
    positions = np.zeros((4, 3), dtype=np.float32)
    with pytest.raises(ValueError, match="attribute 'speed'"):
        meniscus.reconstruct(positions, 0.025, attributes={"speed": np.zeros(3)})


def test_broken_file_raises_format_error_naming_it(tmp_path, shared):
    data = (shared / BUNNY).read_bytes()
    broken = tmp_path / "broken.vtk"
    broken.write_bytes(data[: len(data) // 2])
    with pytest.raises(meniscus.FormatError, match="broken.vtk"):
        meniscus.read_particles(broken)
    assert issubclass(meniscus.FormatError, ValueError)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_positions_are_read_in_place_and_results_own_the_core_buffers(shared, dtype):
    positions = np.ascontiguousarray(meniscus.read_particles(shared / BUNNY).positions, dtype=dtype)
    positions = np.repeat(positions, 20, axis=0)  # large enough that a copy would stand out
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        mesh = meniscus.reconstruct(positions, 0.025, cube_size=1.0, smoothing_iterations=0, threads=1)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # numpy allocations are traced (the core's are not): converting or copying the positions would show here.
    assert peak - before < positions.nbytes / 4, f"{peak - before} bytes allocated by Python for {positions.nbytes}"
    for array in (mesh.vertices, mesh.triangles, mesh.normals):
        # The arrays wrap the core's vectors (kept alive by a capsule) instead of copies.
        assert not array.flags.owndata and type(array.base).__name__ == "PyCapsule"


def test_gil_is_released_during_reconstruction(shared):
    """While one thread reconstructs, another keeps running Python."""
    positions = meniscus.read_particles(shared / "sequence/double_dam_break_0030.vtk").positions
    ticks = []
    done = threading.Event()

    def ticker():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    thread = threading.Thread(target=ticker)
    thread.start()
    start = time.perf_counter()
    meniscus.reconstruct(positions, 0.025, cube_size=0.5, threads=1)
    end = time.perf_counter()
    done.set()
    thread.join()
    during = [t for t in ticks if start < t < end]
    assert len(during) >= 0.3 * (end - start) / 0.002, "the GIL was held during the reconstruction"


def test_write_and_read_mesh_round_trip(tmp_path, shared):
    particles = meniscus.read_particles(shared / BUNNY)
    mesh = meniscus.reconstruct(particles.positions, 0.025, cube_size=1.0,
                                attributes={"velocity": particles.attributes["velocity"]})
    path = tmp_path / "bunny.ply"
    mesh.write(path)
    back = meniscus.read_mesh(path)
    np.testing.assert_array_equal(back.vertices, mesh.vertices)
    np.testing.assert_array_equal(back.triangles, mesh.triangles)
    np.testing.assert_allclose(back.normals, mesh.normals)
    np.testing.assert_allclose(back.attributes["velocity"], mesh.attributes["velocity"])
