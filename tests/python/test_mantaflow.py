"""Mantaflow caches baked by Debian's Blender 3.4 (tests/mantaflow/bake.sh, into build/mantaflow/): the particles
land inside Mantaflow's own surface, their velocities are in m/s, the bobj mesh has Blender's volume, and the CLI
reconstructs a pp_{}.uni sequence."""
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

import meniscus
from conftest import BUILD, ROOT

BAKES = BUILD / "mantaflow"


@pytest.fixture(scope="module")
def baked():
    """The baked caches; bakes them when missing (tests/mantaflow/bake.sh keeps what is up to date)."""
    subprocess.run(["bash", str(ROOT / "tests/mantaflow/bake.sh")], check=True, capture_output=True, timeout=600,
                   env={**os.environ, "MENISCUS_BUILD": str(BUILD)})
    return BAKES


def winding_numbers(mesh, points):
    """Generalised winding number of a closed triangle mesh at each point: ~1 inside, ~0 outside."""
    vertices = np.asarray(mesh.vertices, dtype=float)
    triangles = np.asarray(mesh.triangles)
    out = []
    for p in points:
        a, b, c = (vertices[triangles[:, k]] - p for k in range(3))
        la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
        det = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la + \
            np.einsum("ij,ij->i", c, a) * lb
        out.append(np.arctan2(det, den).sum() / (2 * np.pi))
    return np.array(out)


def enclosed_volume(mesh):
    v = np.asarray(mesh.vertices, dtype=float)
    t = np.asarray(mesh.triangles)
    return np.einsum("ij,ij->i", v[t[:, 0]], np.cross(v[t[:, 1]], v[t[:, 2]])).sum() / 6.0


@pytest.mark.parametrize("scene, frame", [("pool", 10), ("moving_obstacle", 20), ("open_top", 24), ("splash", 18)])
def test_particles_lie_inside_mantaflows_own_surface(baked, scene, frame):
    cache = baked / f"{scene}_UNI" / "cache"
    reference = json.loads((baked / f"{scene}_UNI" / "scene.json").read_text())["mantaflow_mesh_volume"][str(frame)]
    mesh = meniscus.read_mesh(cache / f"mesh/fluid_mesh_{frame:04d}.bobj.gz")
    # Placed as Blender shows it: the same enclosed volume as Blender's evaluated domain mesh.
    assert enclosed_volume(mesh) == pytest.approx(reference, rel=1e-4)
    particles = meniscus.read_particles(cache / f"data/pp_{frame:04d}.uni")
    assert len(particles) > 500
    sample = particles.positions[np.random.default_rng(7).choice(len(particles), 250, replace=False)]
    inside = winding_numbers(mesh, sample.astype(float)) > 0.5
    # FLIP particles sit under Mantaflow's surface; in a thin jet some are in sheets thinner than its mesh resolves,
    # but still within half a cell (2 m / 32 / 2) of it.
    cell = 2.0 / 32
    nearest = np.sqrt(((sample[:, None, :] - np.asarray(mesh.vertices)[None]) ** 2).sum(axis=-1)).min(axis=1)
    assert inside.mean() >= 0.9, f"{scene} frame {frame}: {inside.mean():.3f} of the particles inside"
    assert (inside | (nearest < cell / 2)).all(), f"{scene} frame {frame}: particles {np.flatnonzero(~inside)} outside"


def test_velocities_are_metres_per_second(baked):
    # The pool's sphere falls freely at first: its particles' mean vertical speed grows by g / fps per frame.
    cache = baked / "pool_UNI" / "cache"
    speeds = []
    for frame in (3, 4, 5):
        particles = meniscus.read_particles(cache / f"data/pp_{frame:04d}.uni")
        falling = particles.positions[:, 2] > 0.55
        speeds.append(particles.attributes["velocity"][falling, 2].mean())
    gain = np.diff(speeds)
    assert gain == pytest.approx([-9.81 / 24] * 2, rel=0.1), speeds


def test_cli_reconstructs_a_pp_sequence(baked, cli, tmp_path):
    stats = tmp_path / "stats.json"
    result = subprocess.run([cli, "reconstruct", str(baked / "pool_UNI/cache/data/pp_{}.uni"), "-o",
                             str(tmp_path / "pool_{}.ply"), "-r", "0.03", "-c", "0.5", "-s", "9", "-e", "10",
                             "--stats", str(stats)], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    for frame in (9, 10):
        mesh = meniscus.read_mesh(tmp_path / f"pool_{frame:04d}.ply")
        low, high = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        # In the domain (2 x 2 m, floor at z = 0), not in grid cells (0..32).
        assert low[2] > -0.1 and high[2] < 1.6 and high[0] < 1.1 and low[0] > -1.1, (low, high)
    assert json.loads(stats.read_text())["frames"][0]["counts"]["particles"] > 1000


def test_the_vel_grid_and_a_cache_without_config_are_refused_by_name(baked, tmp_path):
    data = baked / "pool_UNI" / "cache" / "data"
    with pytest.raises(meniscus.FormatError, match="a Mantaflow grid"):
        meniscus.read_particles(data / "vel_0005.uni")
    lone = tmp_path / "data"
    lone.mkdir()
    (lone / "pp_0005.uni").write_bytes((data / "pp_0005.uni").read_bytes())
    with pytest.raises(meniscus.FormatError, match="config_0005.uni, which does not exist"):
        meniscus.read_particles(lone / "pp_0005.uni")


@pytest.mark.parametrize("name", ["pp_0005.uni", "pp_{}.uni", "pp_####.uni"])
def test_frame_patterns_list_the_particle_files_only(baked, name):
    from meniscus import sequence
    frames = sequence.parse_pattern(str(baked / "pool_UNI/cache/data" / name)).list_frames()
    assert sorted(frames) == list(range(1, 25))
    assert all(pathlib.Path(path).name == f"pp_{frame:04d}.uni" for frame, path in frames.items())


@pytest.mark.parametrize("frame", [1, 10, 24])
def test_openvdb_points_match_the_uni_particles_of_the_same_simulation(baked, frame):
    # The same scene baked with data format OpenVDB: Mantaflow writes the same particles as a point data grid
    # (half-float voxel offsets, Blosc LZ4 pages) beside a velocity grid; placed and converted like the UNI cache.
    vdb = meniscus.read_particles(baked / f"pool_OPENVDB/cache/data/fluid_data_{frame:04d}.vdb")
    uni = meniscus.read_particles(baked / f"pool_UNI/cache/data/pp_{frame:04d}.uni")
    assert len(vdb) == len(uni) > 10000
    match, gap = nearest(uni.positions, vdb.positions)
    assert np.percentile(gap, 99) < 2e-5  # half floats of a voxel offset: 0.0625 m * 2^-11
    assert len(np.unique(match)) > 0.99 * len(vdb)
    assert set(vdb.attributes) == {"velocity"}
    speed_gap = np.abs(vdb.attributes["velocity"] - uni.attributes["velocity"][match]).max(axis=1)
    assert np.percentile(speed_gap, 99) < 2e-3


def nearest(points, queries, candidates=32):
    """Index of and distance to the nearest of `points` for each query, among the neighbours in x order."""
    order = np.argsort(points[:, 0], kind="stable")
    start = np.clip(np.searchsorted(points[order, 0], queries[:, 0] - 1e-4) - 2, 0, max(len(points) - candidates, 0))
    window = order[start[:, None] + np.arange(min(candidates, len(points)))]
    distance = np.linalg.norm(points[window] - queries[:, None, :], axis=2)
    best = distance.argmin(axis=1)
    return window[np.arange(len(queries)), best], distance[np.arange(len(queries)), best]


def test_cli_reconstructs_an_openvdb_sequence(baked, cli, tmp_path):
    result = subprocess.run([cli, "reconstruct", str(baked / "pool_OPENVDB/cache/data/fluid_data_{}.vdb"), "-o",
                             str(tmp_path / "pool_{}.ply"), "-r", "0.03", "-c", "0.5", "-s", "12", "-e", "12"],
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    mesh = meniscus.read_mesh(tmp_path / "pool_0012.ply")
    assert mesh.vertices[:, 2].min() > -0.1 and np.abs(mesh.vertices[:, :2]).max() < 1.1
    from meniscus import sequence
    frames = sequence.parse_pattern(str(baked / "pool_OPENVDB/cache/data/fluid_data_0003.vdb")).list_frames()
    assert sorted(frames) == list(range(1, 25))
