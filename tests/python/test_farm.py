"""Farm work with the built command line: the parameters file, safe outputs (temporary name + rename,
--skip-existing, exit codes), and Open Job Description bundles run by the real `openjd` runner."""
import json
import os
import pathlib
import signal
import subprocess
import time

import pytest

from meniscus import farm
from meniscus.parameters import PARAMETERS

from farm_support import (FRAMES, PIPELINE, SEQUENCE, environment, farm_python, local_run, make_sequence, meshes,
                          python_command)


def run(*command, timeout=300, **kwargs):
    return subprocess.run([str(c) for c in command], capture_output=True, text=True, timeout=timeout, **kwargs)


def other_value(p):
    """An allowed value of a schema parameter other than its default."""
    if p.type == "flag":
        return not p.python_default
    if p.type == "vector3":
        return [-1.0, -2.0, -3.0] if p.name.endswith("_min") else [4.0, 5.0, 6.5]
    default = p.default
    for candidate in (p.suggested, p.soft_maximum, p.soft_minimum, default + 1, default * 0.5, (p.minimum + p.maximum) / 2):
        if candidate != default and p.problem(candidate) is None and (p.type != "count" or float(candidate).is_integer()):
            return int(candidate) if p.type == "count" else float(candidate)
    raise AssertionError(f"no other value for {p.name}")


def test_parameters_file_round_trips_every_parameter(cli, tmp_path):
    values = {p.name: other_value(p) for p in PARAMETERS}
    written = tmp_path / "python.json"
    written.write_text(farm.parameters_file_text(values, input="in/fluid_{}.vtk", output="out/s_{}.ply", start=3, end=9,
                                                 attributes=["velocity"]))
    saved = tmp_path / "native.json"
    result = run(cli, "reconstruct", "--parameters", written, "--save-parameters", saved)
    assert result.returncode == 0, result.stderr
    document = json.loads(saved.read_text())
    assert document["parameters"] == values  # every parameter, read by the core and written back unchanged
    assert set(document["parameters"]) == {p.name for p in PARAMETERS}
    assert (document["input"], document["output"], document["start"], document["end"]) == ("in/fluid_{}.vtk", "out/s_{}.ply", 3, 9)
    assert document["interpolate_attributes"] == ["velocity"]
    # The core's own file read back gives the same file, and flags beside the file win over it.
    again = tmp_path / "again.json"
    assert run(cli, "reconstruct", "--parameters", saved, "--save-parameters", again).returncode == 0
    assert again.read_text() == saved.read_text()
    assert run(cli, "reconstruct", "--parameters", saved, "-c", "2", "--frames", "4-5", "--save-parameters", again).returncode == 0
    changed = json.loads(again.read_text())
    assert changed["parameters"]["cube_size"] == 2.0 and (changed["start"], changed["end"]) == (4, 5)
    assert changed["parameters"]["smoothing_iterations"] == values["smoothing_iterations"]


@pytest.mark.parametrize("parameters, key, words", [
    ({"cube_sise": 1.0}, "parameters.cube_sise", "unknown parameter"),
    ({"cube_size": "big"}, "parameters.cube_size", 'got "big"'),
    ({"cube_size": 0}, "parameters.cube_size", "must be a number greater than 0, got 0"),
    ({"smoothing_iterations": 2.5}, "parameters.smoothing_iterations", "whole number"),
    ({"normals": 1}, "parameters.normals", "must be true or false, got 1"),
    ({"mesh_aabb_min": [0, 1]}, "parameters.mesh_aabb_min", "three numbers"),
])
def test_parameters_file_refusals_name_the_key(cli, tmp_path, parameters, key, words):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"meniscus_parameters": 1, "parameters": {"particle_radius": 0.025, **parameters}}))
    result = run(cli, "reconstruct", "x_{}.vtk", "--parameters", path, "--save-parameters", tmp_path / "out.json")
    assert result.returncode == 2
    assert f"{path}: {key}: " in result.stderr and words in result.stderr, result.stderr
    assert not (tmp_path / "out.json").exists()


def test_parameters_file_top_level_refusals(cli, tmp_path):
    path = tmp_path / "bad.json"
    for document, words in (({"meniscus_parameters": 1, "frames": [1, 2]}, "frames: unknown key"),
                            ({"parameters": {}}, "meniscus_parameters: missing"),
                            ({"meniscus_parameters": 1, "start": "one"}, "start: must be a whole frame number")):
        path.write_text(json.dumps(document))
        result = run(cli, "reconstruct", "x.vtk", "-r", "0.025", "--parameters", path)
        assert result.returncode == 2 and words in result.stderr, result.stderr
    path.write_text("{not json")
    result = run(cli, "reconstruct", "x.vtk", "-r", "0.025", "--parameters", path)
    assert result.returncode == 2 and "not a JSON parameters file" in result.stderr
    # Without the file, the radius is still required, by its flag's name.
    result = run(cli, "reconstruct", "x.vtk")
    assert result.returncode == 2 and "--particle-radius is required" in result.stderr
    with pytest.raises(ValueError, match="cube_size"):
        farm.parameters_file_text({"particle_radius": 0.025, "cube_size": -1})


def test_skip_existing_redoes_only_missing_and_failures_are_named(cli, tmp_path):
    inputs = make_sequence(tmp_path / "in", corrupt={3})
    out = tmp_path / "out" / "surface_{}.ply"
    stats = tmp_path / "stats.json"
    result = run(cli, "reconstruct", inputs, "-o", out, "--frames", "1-6", *PIPELINE, "--stats", stats)
    assert result.returncode == 1
    assert "1 of 6 frames failed: 3" in result.stderr and "fluid_0003.vtk" in result.stderr
    report = json.loads(stats.read_text())
    assert report["failed"] == [3] and report["failed_frames"] == 1
    written = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "out").iterdir() if p.suffix != ".meniscus"}
    assert sorted(written) == [f"surface_{n:04d}.ply" for n in FRAMES if n != 3]  # no temporary file is left
    assert all((tmp_path / "out" / (name + ".meniscus")).is_file() for name in written)  # each with its provenance
    (tmp_path / "out" / "surface_0005.ply").unlink()
    # Frame 3 repaired, alone: a particle file rewritten since makes its output stale (test_provenance.py).
    (tmp_path / "in" / "fluid_0003.vtk").write_bytes((SEQUENCE / "double_dam_break_0003.vtk").read_bytes())
    result = run(cli, "reconstruct", inputs, "-o", out, "--frames", "1-6", *PIPELINE, "--skip-existing", "--stats", stats)
    assert result.returncode == 0, result.stderr
    assert "4 of 6 frames skipped" in result.stderr
    report = json.loads(stats.read_text())
    assert [f["frame"] for f in report["frames"] if "skipped" not in f] == [3, 5]
    for name, mtime in written.items():
        if name != "surface_0005.ply":
            assert (tmp_path / "out" / name).stat().st_mtime_ns == mtime, name


def test_killed_run_leaves_no_partial_mesh(cli, shared, tmp_path):
    """SIGKILL while the mesh is being written: the output name never holds a partial mesh."""
    frame = shared / "splashsurf" / "hilbert_46843_particles.bgeo"
    out = tmp_path / "surface.obj"  # text, the slowest to write
    for attempt in range(5):
        process = subprocess.Popen([cli, "reconstruct", frame, "-o", out, "-r", "0.025", "-c", "0.3", "-q"],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            deadline = time.monotonic() + 120
            partial = []
            while process.poll() is None and time.monotonic() < deadline and not partial:
                partial = [name for name in os.listdir(tmp_path) if name.startswith(".partial-")]
                time.sleep(0.0005)
            if partial and process.poll() is None:
                process.send_signal(signal.SIGKILL)
                process.wait(timeout=10)
                assert not out.exists()
                assert partial == [f".partial-{process.pid}-surface.obj"]
                return
        finally:
            if process.poll() is None:
                process.kill()
                process.wait(timeout=10)
        out.unlink(missing_ok=True)
    pytest.fail("the write was never caught in progress in 5 runs")


# ---- Open Job Description ------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def openjd():
    return farm_python().parent / "openjd"


def write_bundle(cli, tmp_path, inputs, chunk=2):
    bundle = tmp_path / "bundle"
    result = run(*python_command(), "farm", "openjd", inputs, "-o", tmp_path / "out" / "surface_{}.ply", "-s", 1, "-e", 6,
                 "--chunk-size", chunk, *PIPELINE, "--meniscus-command", cli, "--bundle", bundle, env=environment())
    assert result.returncode == 0, result.stderr
    # The folders outside the bundle are given as openjd run's -p (OpenJD allows PATH defaults inside it only).
    command = result.stdout.splitlines()[1].split()
    assert command[:3] == ["openjd", "run", str(bundle / "template.yaml")] and "-p" in command
    return command[1:]


def test_openjd_bundle_runs_in_chunks_like_a_local_run(cli, openjd, tmp_path):
    reference = meshes(local_run(cli, tmp_path / "local"))
    openjd_run = write_bundle(cli, tmp_path, make_sequence(tmp_path / "in"))
    bundle = tmp_path / "bundle"
    assert {p.name for p in bundle.iterdir()} == {"template.yaml", "parameter_values.yaml", "asset_references.yaml",
                                                   "parameters.json"}
    assert run(openjd, "check", bundle / "template.yaml").returncode == 0
    started = time.monotonic()
    result = run(openjd, *openjd_run)
    seconds = time.monotonic() - started
    assert result.returncode == 0, result.stdout + result.stderr
    for chunk in ("1-2", "3-4", "5-6"):
        assert f"Frame(CHUNK[INT]) = {chunk}" in result.stdout  # three tasks of two frames
    assert meshes(tmp_path / "out") == reference and len(reference) == 6
    print(f"openjd run: 6 frames in chunks of 2: {seconds:.1f} s")

    # A re-run after losing one mesh redoes that one only.
    mtimes = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "out").glob("*.ply")}
    (tmp_path / "out" / "surface_0004.ply").unlink()
    assert run(openjd, *openjd_run).returncode == 0
    assert meshes(tmp_path / "out") == reference
    redone = [name for name, mtime in mtimes.items() if (tmp_path / "out" / name).stat().st_mtime_ns != mtime]
    assert redone == ["surface_0004.ply"]


def test_openjd_chunk_with_a_corrupt_frame_fails_naming_it(cli, openjd, tmp_path):
    reference = meshes(local_run(cli, tmp_path / "local"))
    openjd_run = write_bundle(cli, tmp_path, make_sequence(tmp_path / "in", corrupt={3}))
    outcomes = {}
    for chunk in ("1-2", "3-4", "5-6"):  # each task as a farm would run it, one session each
        result = run(openjd, *openjd_run, "--task-param", f"Frame={chunk}")
        outcomes[chunk] = result
    failed = outcomes["3-4"]
    assert failed.returncode != 0
    assert "fluid_0003.vtk" in failed.stdout and "frames failed: 3" in failed.stdout
    assert outcomes["1-2"].returncode == 0 and outcomes["5-6"].returncode == 0
    produced = meshes(tmp_path / "out")
    assert sorted(produced) == [f"surface_{n:04d}.ply" for n in FRAMES if n != 3]
    assert all(produced[name] == reference[name] for name in produced)
