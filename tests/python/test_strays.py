"""Stray blobs: small pieces removed by particle count or volume, off by default, stable as droplets move."""
import numpy as np

import meniscus

R = 0.025

def block_and_droplets(offset=(0.0, 0.0, 0.0)):
    """A 6 x 6 x 6 block at spacing 2 r, and droplets of 1, 3 and 10 particles well apart from it and each other."""
    g = np.arange(6) * 2 * R
    block = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    droplets = []
    for count, centre in ((1, (1.0, 0, 0)), (3, (0, 1.0, 0)), (10, (0, 0, 1.0))):
        droplets.append(np.asarray(centre) + np.arange(count)[:, None] * np.array([1.6 * R, 0, 0]))
    return (np.vstack([block, *droplets]) + np.asarray(offset)).astype(np.float32)

def _components(mesh):
    # Union-find over triangle corners: the number of connected pieces.
    parent = np.arange(len(mesh.vertices))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for a, b, c in mesh.triangles:
        for u, v in ((a, b), (b, c)):
            ru, rv = find(u), find(v)
            if ru != rv:
                parent[max(ru, rv)] = min(ru, rv)
    return len({find(v) for v in range(len(mesh.vertices))})

def test_off_by_default_every_droplet_stays():
    mesh = meniscus.reconstruct(block_and_droplets(), particle_radius=R)
    assert _components(mesh) == 4
    assert "stray_components_removed" not in mesh.stats["counts"]

def test_pieces_of_fewer_particles_are_removed_with_count_and_volume_in_the_stats():
    kept = meniscus.reconstruct(block_and_droplets(), particle_radius=R)
    mesh = meniscus.reconstruct(block_and_droplets(), particle_radius=R, stray_min_particles=5)
    counts = mesh.stats["counts"]
    assert _components(mesh) == 2  # the block and the 10-particle droplet
    assert counts["stray_components_removed"] == 2 and counts["stray_particles_removed"] == 4
    assert counts["stray_volume_removed"] > 0
    assert len(mesh.vertices) < len(kept.vertices)

def test_volume_rule_removes_what_encloses_less_than_the_minimum():
    # The lone particle's drop encloses ~1.7 particle volumes, the 3-particle one ~4.7, the 10-particle one ~17.
    particle_volume = 4 / 3 * np.pi * R**3
    mesh = meniscus.reconstruct(block_and_droplets(), particle_radius=R, stray_min_volume=2.0)
    assert mesh.stats["counts"]["stray_components_removed"] == 1 and _components(mesh) == 3
    assert 1.0 < mesh.stats["counts"]["stray_volume_removed"] / particle_volume < 2.0
    mesh = meniscus.reconstruct(block_and_droplets(), particle_radius=R, stray_min_volume=8.0)
    assert mesh.stats["counts"]["stray_components_removed"] == 2 and _components(mesh) == 2

def test_the_rule_is_the_same_wherever_the_droplets_are():
    # A sequence moves droplets; the particle-count rule must keep or drop the same ones.
    for offset in ((0, 0, 0), (0.013, -0.021, 0.007), (0.3, 0.2, -0.1)):
        mesh = meniscus.reconstruct(block_and_droplets(offset), particle_radius=R, stray_min_particles=5)
        assert mesh.stats["counts"]["stray_components_removed"] == 2
        assert _components(mesh) == 2

def test_a_negative_minimum_is_refused_in_the_users_terms():
    try:
        meniscus.reconstruct(block_and_droplets(), particle_radius=R, stray_min_volume=-1)
    except ValueError as error:
        assert "stray_min_volume" in str(error) and "-1" in str(error)
    else:
        raise AssertionError("a negative minimum volume was accepted")
