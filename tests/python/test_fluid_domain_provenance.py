"""A fluid domain shapes a filled surface as much as the parameters do: its provenance record carries the domain
(borders, band, gravity, grid, obstacles, the domain object's matrix), so a bake made with another domain is stale;
and the Mantaflow readers give the domain object's matrix the frame was simulated with (what the add-on needs to move
a frame with a domain moved since its bake)."""
import json
import os
import subprocess

import numpy as np

import meniscus
from meniscus import _core, cache
from conftest import BUILD, ROOT

IDENTITY = [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0]


def domain(**changes):
    values = {"closed_borders": [True] * 6, "gravity": [0.0, 0.0, -1.0], "band_width_cells": 3.0,
              "obstacles": [np.arange(9, dtype=np.float32)], "object_to_world": IDENTITY}
    values.update(changes)
    return values


def test_the_fluid_domain_is_part_of_the_record(tmp_path):
    source, mesh = tmp_path / "pp_0001.uni", tmp_path / "surface_0001.npz"
    source.write_bytes(b"particles")
    mesh.write_bytes(b"mesh")
    arguments = {"particle_radius": 0.03, "fluid_domain": domain()}
    record = cache.provenance(str(source), arguments)
    assert "fluid_domain" in arguments  # the caller's arguments are left as they were
    _core.write_provenance(str(mesh), record)
    assert cache.stale_reason(str(mesh), cache.provenance(str(source), {**arguments, "fluid_domain": domain()})) == ""
    moved = [np.arange(9, dtype=np.float32) + 0.5]
    for changed in (domain(closed_borders=[True] * 5 + [False]), domain(band_width_cells=5.0), domain(obstacles=moved),
                    domain(gravity=[0.0, -1.0, 0.0]), domain(object_to_world=IDENTITY[:12] + [1.0, 0, 0, 1.0]),
                    domain(mesh_upres=3), domain(mesh_particle_radius=1.5), domain(mesh_smoothen_neg=0),
                    domain(mesh_concave_upper=3.0)):
        reason = cache.stale_reason(str(mesh), cache.provenance(str(source), {**arguments, "fluid_domain": changed}))
        assert reason.startswith("made with another fluid domain"), (changed, reason)
    assert cache.stale_reason(str(mesh), cache.provenance(str(source), {"particle_radius": 0.03})) == \
        "made with a fluid domain, now without"
    # The parameters still come first, and alone (the particle file gone) the domain is checked too.
    assert cache.stale_reason(str(mesh), cache.provenance(None, arguments)) == ""
    assert cache.stale_reason(str(mesh), cache.provenance(None, {**arguments, "fluid_domain": domain(
        band_width_cells=1.0)})).startswith("made with another fluid domain")


def test_the_mantaflow_reader_gives_the_domain_objects_matrix():
    bakes = BUILD / "mantaflow"
    subprocess.run(["bash", str(ROOT / "tests/mantaflow/bake.sh")], check=True, capture_output=True, timeout=600,
                   env={**os.environ, "MENISCUS_BUILD": str(BUILD)})
    baked = json.loads((bakes / "pool_UNI" / "scene.json").read_text())
    for path in (bakes / "pool_UNI/cache/data/pp_0010.uni", bakes / "pool_OPENVDB/cache/data/fluid_data_0010.vdb"):
        read = meniscus.read_particles(path).fluid_domain
        # Column-major, as Blender and the cache's config keep it: the transpose of the rows scene.json lists.
        assert np.allclose(np.reshape(read["object_to_world"], (4, 4)).T, baked["matrix_world"], atol=1e-6), path
        # What the reader gives, the core takes back (a dict passed on unchanged to reconstruct).
        positions = meniscus.read_particles(path).positions
        mesh = meniscus.reconstruct(positions[:2000], particle_radius=0.03, cube_size=1.5, fluid_domain=read)
        assert len(mesh.triangles) > 0
