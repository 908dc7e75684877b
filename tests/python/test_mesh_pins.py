"""Refactors keep behaviour: every shared frame, under five parameter sets, gives the pinned mesh bit for bit (vertices,
triangles, normals, attributes), with 1 thread and with 2 (see mesh_pins.py; pins in tests/data/mesh_pins.json)."""
import json

import meniscus
import pytest

import mesh_pins


@pytest.mark.parametrize("threads", [1, 2])
def test_meshes_match_their_pins(threads):
    pinned = json.loads(mesh_pins.PINS.read_text())
    computed = mesh_pins.compute(meniscus, threads=threads)
    assert sorted(computed) == sorted(pinned)
    changed = {case: (pinned[case], computed[case]) for case in pinned if computed[case] != pinned[case]}
    assert not changed, changed
