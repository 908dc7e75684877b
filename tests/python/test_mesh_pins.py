"""Refactors keep behaviour: every shared frame, under five parameter sets, gives the pinned mesh bit for bit (vertices,
triangles, normals, attributes), with 1 thread and with 2 (see mesh_pins.py; pins in tests/data/mesh_pins.json)."""
import json
import os
import pathlib
import subprocess
import sys

import conftest
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


def test_the_sse_path_of_the_colour_field_gives_the_pinned_bits():
    # The sampler takes AVX-512 where the CPU has it, else SSE (surface/level_set.cpp). The test above runs the path
    # this CPU has; this one forces SSE (MENISCUS_SIMD=sse, read once per process, hence the fresh process).
    frames = ["bunny_frame_14_7705_particles.vtk", "hilbert2_7954_particles.vtk"]
    script = (
        "import json, sys, meniscus, mesh_pins\n"
        f"mesh_pins.FRAMES = {frames!r}\n"
        "print(json.dumps(mesh_pins.compute(meniscus, threads=2)))\n"
    )
    environment = dict(os.environ, MENISCUS_SIMD="sse",
                       PYTHONPATH=os.pathsep.join([str(conftest.BUILD / "python"), str(pathlib.Path(__file__).parent)]))
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=environment, timeout=600)
    assert result.returncode == 0, result.stderr
    computed = json.loads(result.stdout)
    pinned = json.loads(mesh_pins.PINS.read_text())
    assert len(computed) == len(frames) * len(mesh_pins.CASES)
    changed = {case: (pinned[case], computed[case]) for case in computed if computed[case] != pinned[case]}
    assert not changed, changed
