"""Busy machines: a frame with the automatic thread count takes the cores other programs leave free when it starts
(native/core/base/machine_load.h says why), through the CLI and the Python package alike; a count the user chose is
kept, and the mesh is the same either way. Two plain busy loops hold two cores for the length of each check."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import BUILD

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the machine's load is read on Linux only")

FRAME = "double_dam_break_frame_26_4732_particles.vtk"


@pytest.fixture
def two_busy_loops():
    loops = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(2)]
    try:
        yield
    finally:
        for loop in loops:
            loop.kill()
            loop.wait()


def cores():
    return len(os.sched_getaffinity(0))


def cli_frame(cli, tmp_path, shared, threads, name):
    stats = tmp_path / f"{name}.json"
    subprocess.run([cli, "reconstruct", str(shared / "splashsurf" / FRAME), "-o", str(tmp_path / f"{name}.ply"), "-r", "0.025",
                    "-c", "1.0", "-n", str(threads), "--stats", str(stats), "-q"], check=True, capture_output=True)
    return json.loads(stats.read_text())["frames"][0]["counts"]["threads"], (tmp_path / f"{name}.ply").read_bytes()


def test_the_cli_leaves_the_cores_of_busy_programs(cli, tmp_path, shared, two_busy_loops):
    taken, automatic_mesh = cli_frame(cli, tmp_path, shared, 0, "automatic")
    # Two loops run all the time (and whatever else the machine does): at most the other cores, at least one.
    assert 1 <= taken <= max(1, cores() - 2)
    chosen, chosen_mesh = cli_frame(cli, tmp_path, shared, 2, "chosen")
    assert chosen == 2  # the user's count stays
    assert automatic_mesh == chosen_mesh


def test_the_python_package_leaves_the_cores_of_busy_programs(shared, two_busy_loops):
    import meniscus
    particles = meniscus.read_particles(shared / "splashsurf" / FRAME)
    automatic = meniscus.reconstruct(particles.positions, 0.025, cube_size=1.0)
    assert 1 <= automatic.stats["counts"]["threads"] <= max(1, cores() - 2)
    chosen = meniscus.reconstruct(particles.positions, 0.025, cube_size=1.0, threads=2)
    assert chosen.stats["counts"]["threads"] == 2
    assert np.array_equal(automatic.vertices, chosen.vertices) and np.array_equal(automatic.triangles, chosen.triangles)
