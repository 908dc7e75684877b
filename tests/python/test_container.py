"""The container through the Python API and the command line (splashsurf's flag spelling): the surface of a block of
fluid cut by a box stays inside it, closed by flat faces on the walls; an open cut; the particle box's count."""
import json
import subprocess

import numpy as np
import pytest

import meniscus

RADIUS = 0.025
LOWER, UPPER = (0.1031, 0.0977, 0.0712), (0.4969, 0.5023, 1.0)


def fluid_block():
    # Particles on a lattice of spacing 2r filling [0, 0.6] x [0, 0.6] x [0, 0.4]; the box cuts four sides and the floor.
    axes = [RADIUS * (1 + 2 * np.arange(n)) for n in (12, 12, 8)]
    return np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3).astype(np.float32)


def inside(vertices):
    lower, upper = np.float32(LOWER), np.float32(UPPER)
    return np.all((vertices >= lower) & (vertices <= upper), axis=1)


@pytest.mark.parametrize("smoothing", [{}, {"smoothing_reach": 4.28}], ids=["iterations", "physical reach"])
def test_capped_box_through_the_api(smoothing):
    mesh = meniscus.reconstruct(fluid_block(), RADIUS, mesh_aabb_min=LOWER, mesh_aabb_max=UPPER, threads=2, **smoothing)
    assert meniscus.check_mesh(mesh)["ok"]
    assert inside(mesh.vertices).all()
    on_floor = mesh.vertices[:, 2] == np.float32(LOWER[2])
    assert on_floor.sum() > 100  # the cap on the floor lies on its plane exactly
    floor_triangles = on_floor[mesh.triangles].all(axis=1)
    assert floor_triangles.sum() > 100


def test_open_cut_and_clamping_through_the_api():
    block = fluid_block()
    cut = meniscus.reconstruct(block, RADIUS, mesh_aabb_min=LOWER, mesh_aabb_max=UPPER, mesh_aabb_cap=False)
    assert not meniscus.check_mesh(cut)["ok"]  # open where the box cut it
    assert inside(cut.vertices)[cut.triangles].any(axis=1).all()
    clamped = meniscus.reconstruct(block, RADIUS, mesh_aabb_min=LOWER, mesh_aabb_max=UPPER, mesh_aabb_cap=False,
                                   mesh_aabb_clamp_verts=True)
    assert inside(clamped.vertices).all()
    assert len(clamped.triangles) == len(cut.triangles)


def test_particle_box_counts_the_particles_dropped():
    block = fluid_block()
    mesh = meniscus.reconstruct(block, RADIUS, particle_aabb_min=(-1, -1, -1), particle_aabb_max=(0.3, 10, 10))
    assert mesh.stats["counts"]["particles_outside_box"] == int((block[:, 0] > 0.3).sum())
    assert mesh.stats["counts"]["particles"] == int((block[:, 0] <= 0.3).sum())


def test_a_box_with_one_corner_is_refused_naming_it():
    with pytest.raises(ValueError, match="mesh_aabb_min"):
        meniscus.reconstruct(fluid_block(), RADIUS, mesh_aabb_min=LOWER)


def test_splashsurf_flags_on_the_command_line(cli, tmp_path):
    fluid_block().astype("<f4").tofile(tmp_path / "block.xyz")
    stats = tmp_path / "stats.json"
    line = ["reconstruct", "block.xyz", "-r=0.025", "-c=0.5", "-o", "capped.ply", "--stats", "stats.json",
            "--mesh-aabb-min", *map(str, LOWER), "--mesh-aabb-max", *map(str, UPPER),
            "--particle-aabb-min", "-1", "-1", "-1", "--particle-aabb-max", "10", "10", "10"]
    result = subprocess.run([cli, *line], capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr
    mesh = meniscus.read_mesh(tmp_path / "capped.ply")
    assert meniscus.check_mesh(mesh)["ok"] and inside(mesh.vertices).all()
    assert json.loads(stats.read_text())["frames"][0]["counts"]["particles_outside_box"] == 0

    line = ["reconstruct", "block.xyz", "-r=0.025", "-c=0.5", "-o", "open.ply", "--mesh-aabb-min", *map(str, LOWER),
            "--mesh-aabb-max", *map(str, UPPER), "--mesh-aabb-cap=off", "--mesh-aabb-clamp-verts=on"]
    result = subprocess.run([cli, *line], capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr
    mesh = meniscus.read_mesh(tmp_path / "open.ply")
    assert inside(mesh.vertices).all() and not meniscus.check_mesh(mesh)["ok"]

    result = subprocess.run([cli, "reconstruct", "block.xyz", "-r=0.025", "-o", "x.ply", "--mesh-aabb-max", "1", "1", "1"],
                            capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert result.returncode != 0 and "--mesh-aabb-max" in result.stderr


def test_add_on_container_bounds_follow_rotation_and_scale_without_blender():
    # The add-on's box from an object's bounds is plain Python (no bpy): load its module from the source tree.
    import importlib.util
    import math
    import pathlib

    path = pathlib.Path(__file__).resolve().parents[2] / "addon/meniscus/blender/container.py"
    spec = importlib.util.spec_from_file_location("meniscus_container", path)
    container = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(container)
    corners = [(x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    c, s = math.cos(math.pi / 4), math.sin(math.pi / 4)
    matrix = [[2 * c, -s, 0, 10], [2 * s, c, 0, 0], [0, 0, 3, -1], [0, 0, 0, 1]]  # scale (2, 1, 3), 45 degrees about z
    lower, upper = container.world_bounds(corners, matrix)
    np.testing.assert_allclose(lower, (10 - 3 * c, -3 * s, -4), atol=1e-12)
    np.testing.assert_allclose(upper, (10 + 3 * c, 3 * s, 2), atol=1e-12)


def test_particle_box_filters_the_attributes_alongside():
    block = fluid_block()
    ids = np.arange(len(block), dtype=np.int32)
    mesh = meniscus.reconstruct(block, RADIUS, particle_aabb_min=(-1, -1, -1), particle_aabb_max=(0.3, 10, 10),
                                attributes={"id": ids})
    kept = set(ids[block[:, 0] <= 0.3].tolist())
    assert mesh.attributes["id"].dtype == np.int32
    assert set(np.unique(mesh.attributes["id"]).tolist()) <= kept  # carried from kept particles only


def test_a_sloped_contact_line_is_straightened_on_the_wall():
    # Fluid whose top rises along x (stepped by the particle layers) against the wall y = LOWER[1]: where the free
    # surface meets the wall, marching cubes leaves a staircase; smoothing along the contact line straightens it.
    columns = [(x, y, z) for x in range(24) for y in range(12) for z in range(40)
               if RADIUS * (1 + 2 * z) <= 0.2 + 0.25 * (x * 2 * RADIUS)]
    block = (RADIUS * (1 + 2 * np.array(columns))).astype(np.float32)
    lower, upper = (0.1031, LOWER[1], -1.0), (1.1, UPPER[1], 2.0)

    def contact_line_roughness(mesh):
        on_wall = mesh.vertices[:, 1] == np.float32(lower[1])
        edges = np.concatenate([mesh.triangles[:, [0, 1]], mesh.triangles[:, [1, 2]], mesh.triangles[:, [2, 0]]])
        crossing = edges[on_wall[edges[:, 0]] & ~on_wall[edges[:, 1]], 0]  # wall vertices next to the free surface
        x, z = mesh.vertices[crossing, 0], mesh.vertices[crossing, 2]
        keep = (x > 0.2) & (x < 1.0) & (z > 0.15)  # the sloped top, away from the other walls
        x, z = x[keep], z[keep]
        return np.std(z - np.polyval(np.polyfit(x, z, 1), x)), len(x)

    raw = meniscus.reconstruct(block, RADIUS, mesh_aabb_min=lower, mesh_aabb_max=upper, smoothing_iterations=0,
                               decimate_barnacles=False)
    smoothed = meniscus.reconstruct(block, RADIUS, mesh_aabb_min=lower, mesh_aabb_max=upper)
    (before, n_before), (after, n_after) = contact_line_roughness(raw), contact_line_roughness(smoothed)
    assert n_before > 50 and n_after > 50
    assert meniscus.check_mesh(smoothed)["ok"]
    assert after < 0.4 * before, (before, after)  # measured: 0.0128 -> 0.0031
