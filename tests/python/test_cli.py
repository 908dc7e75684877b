"""The command-line tool: single frames, sequences with gaps and broken frames, stats, output formats."""
import json
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import meniscus


def run(cli, *args):
    return subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("extension", ["ply", "obj", "vtk"])
def test_single_frame_writes_mesh_and_stats(cli, shared, tmp_path, extension):
    out = tmp_path / f"bunny.{extension}"
    stats = tmp_path / "stats.json"
    result = run(cli, "reconstruct", shared / "splashsurf/bunny_frame_14_7705_particles.vtk", "-o", out, "-r", 0.025, "-l", 2,
                 "-c", 1.0, "-t", 0.6, "--threads", 2, "--stats", stats, "--check-mesh", "-a", "velocity")
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 100000
    report = json.loads(stats.read_text())
    frame = report["frames"][0]
    assert frame["check"]["ok"]
    assert frame["counts"]["particles"] == 7706
    assert {"read", "neighborhood", "density", "level set and marching cubes", "write"} <= set(frame["seconds"])
    assert report["peak_memory_bytes"] > 0
    if extension != "vtk":
        mesh = meniscus.read_mesh(out)
        assert meniscus.check_mesh(mesh)["ok"]
        if extension == "ply":
            assert "velocity" in mesh.attributes and mesh.normals is not None


def test_sequence_with_missing_and_broken_frames_goes_on(cli, shared, tmp_path):
    source = shared / "sequence"
    frames = tmp_path / "in"
    frames.mkdir()
    for n in (10, 11, 13):
        shutil.copy(source / f"double_dam_break_{n:04d}.vtk", frames / f"fluid_{n:04d}.vtk")
    (frames / "fluid_0012.vtk").write_bytes((source / "double_dam_break_0012.vtk").read_bytes()[:5000])  # truncated
    stats = tmp_path / "stats.json"
    result = run(cli, "reconstruct", frames / "fluid_{}.vtk", "-o", tmp_path / "out_{}.ply", "-r", 0.025, "-c", 1.0,
                 "-s", 10, "-e", 14, "--stats", stats)
    assert result.returncode == 1  # some frames failed, the others were written
    assert "fluid_0012.vtk" in result.stderr and "truncated" in result.stderr
    assert "frame 14 is missing" in result.stderr
    for n in (10, 11, 13):
        assert (tmp_path / f"out_{n:04d}.ply").exists()
    assert not (tmp_path / "out_0012.ply").exists()
    report = json.loads(stats.read_text())
    assert report["failed_frames"] == 2
    assert [f.get("failed") is None for f in report["frames"]] == [True, True, False, True, False]


def test_bad_parameters_and_missing_attribute_are_reported(cli, shared, tmp_path):
    frame = shared / "splashsurf/hilbert2_7954_particles.vtk"
    # Each value is refused naming the flag as the user typed it, with the allowed values and the value given.
    result = run(cli, "reconstruct", frame, "-o", tmp_path / "x.ply", "-r", -1)
    assert result.returncode == 2 and "--particle-radius: must be a number greater than 0, got -1" in result.stderr
    result = run(cli, "reconstruct", frame, "-o", tmp_path / "x.ply", "-r", 0.025, "--mesh-smoothing-strength", 0)
    assert result.returncode == 2 and "--mesh-smoothing-strength: must be a number greater than 0 and at most 1, got 0" in result.stderr
    result = run(cli, "reconstruct", frame, "-o", tmp_path / "x.ply", "-r", 0.025, "--mesh-smoothing-iters", 2.5)
    assert result.returncode == 2 and "must be a whole number at least 0, got 2.5" in result.stderr
    result = run(cli, "reconstruct", frame, "-o", tmp_path / "x.ply", "-r", 0.025, "--normals", "maybe")
    assert result.returncode == 2 and "--normals: takes on or off, got 'maybe'" in result.stderr
    result = run(cli, "reconstruct", frame, "-o", tmp_path / "x.ply", "-r", 0.025, "--mesh-smoothing-weights-normalization", "x")
    assert result.returncode == 2 and "takes a number greater than 0, or 0 for automatic (auto), got 'x'" in result.stderr
    result = run(cli, "reconstruct", shared / "splashsurf/hilbert2_7954_particles.vtk", "-o", tmp_path / "x.ply", "-r", 0.025,
                 "-a", "velocity")
    assert result.returncode != 0 and "no particle attribute 'velocity'" in result.stderr and "id" in result.stderr


def test_inspect_reports_quality(cli, shared, tmp_path):
    out, raw = tmp_path / "mesh.ply", tmp_path / "raw.ply"
    assert run(cli, "reconstruct", shared / "splashsurf/double_dam_break_frame_26_4732_particles.vtk", "-o", out,
               "--output-raw-mesh", raw, "-r", 0.025, "-c", 0.5).returncode == 0
    report_path = tmp_path / "report.json"
    result = run(cli, "inspect", out, "--raw", raw, "--json", report_path)
    assert result.returncode == 0, result.stdout + result.stderr
    report = json.loads(report_path.read_text())
    assert report["mesh"]["check"]["ok"]
    assert 0.97 < report["volume_ratio"] < 1.03
    assert report["bumpiness_ratio"] < 0.5
    assert "bumpiness" in result.stdout


def test_every_frame_of_the_shared_sequence_passes_the_mesh_check(cli, shared, tmp_path):
    """The full default pipeline on all 61 frames of the double dam break (spray, sheets, settling pool)."""
    stats = tmp_path / "stats.json"
    result = run(cli, "reconstruct", shared / "sequence/double_dam_break_{}.vtk", "-o", tmp_path / "s_{}.ply", "-r", 0.025,
                 "-c", 0.75, "--check-mesh", "--stats", stats, "-q")
    report = json.loads(stats.read_text())
    assert len(report["frames"]) == 61
    failed = [(f["frame"], f.get("failed")) for f in report["frames"] if f.get("failed")]
    assert not failed and result.returncode == 0, (failed, result.stderr[-2000:])
    assert all(f["check"]["ok"] for f in report["frames"])


@pytest.mark.parametrize("spelling, chosen", [("fluid_{}.vtk", "fluid_7.vtk"), ("fluid_####.vtk", "fluid_0007.vtk")])
def test_command_line_and_add_on_pick_the_same_file_for_two_spellings_of_a_frame(cli, shared, tmp_path, spelling,
                                                                                  chosen):
    # Frame 7 written twice; the spelling of the pattern decides, in every interface (one rule in the core).
    frames = shared / "splashsurf"
    shutil.copy(frames / "double_dam_break_frame_01_4732_particles.vtk", tmp_path / "fluid_7.vtk")
    shutil.copy(frames / "bunny_frame_14_7705_particles.vtk", tmp_path / "fluid_0007.vtk")
    stats = tmp_path / "stats.json"
    result = run(cli, "reconstruct", tmp_path / spelling, "-o", tmp_path / "out_{}.ply", "-r", 0.025, "-c", 1.0,
                 "--stats", stats)
    assert result.returncode == 0, result.stderr
    assert "frame 7: fluid_0007.vtk and fluid_7.vtk; using " + chosen in result.stderr
    assert pathlib.Path(json.loads(stats.read_text())["frames"][0]["input"]).name == chosen
    from meniscus import sequence
    assert pathlib.Path(sequence.parse_pattern(str(tmp_path / spelling)).list_frames()[7]).name == chosen


def test_command_lines_from_splashsurfs_readme_run_unchanged(cli, shared, tmp_path):
    # The benchmark lines of splashsurf's README, on a frame scaled to their radius 0.011 and stored as raw XYZ.
    positions = meniscus.read_particles(shared / "splashsurf/double_dam_break_frame_26_4732_particles.vtk").positions
    (positions * (0.011 / 0.025)).astype("<f4").tofile(tmp_path / "canyon_13353401_particles.xyz")
    for line, output in [
        ("reconstruct canyon_13353401_particles.xyz -r=0.011 -c=1.5 -l=2.0 -t=0.6 --output-dir=out",
         "out/canyon_13353401_particles_surface.vtk"),
        ("reconstruct canyon_13353401_particles.xyz -r=0.011 -c=1.5 -l=2.0 -t=0.6 --subdomain-grid=on",
         "canyon_13353401_particles_surface.vtk"),
        # The README's "full invocation" (on the same file) ...
        ("reconstruct canyon_13353401_particles.xyz -r=0.011 -l=2.0 -c=0.5 -t=0.6 --mesh-smoothing-weights=on "
         "--mesh-smoothing-iters=15 --normals=on --normals-smoothing-iters=10 -o full.vtk", "full.vtk"),
        # ... and every option of its reference list that a pipeline user sets, in its own spelling.
        ("reconstruct canyon_13353401_particles.xyz -r=0.011 -l=2.0 -c=0.75 -t=0.6 -n 2 --mt-particles=on -d=off "
         "--rest-density 1000 --subdomain-grid=on --subdomain-cubes 64 --mesh-cleanup=on --mesh-cleanup-snap-dist 0.3 "
         "--decimate-barnacles=on --keep-verts=off --mesh-smoothing-iters 25 --mesh-smoothing-weights=on "
         "--mesh-smoothing-weights-normalization 13 --output-smoothing-weights=on --normals=on --sph-normals=off "
         "--normals-smoothing-iters 10 --output-raw-normals=off --generate-quads=on --quad-max-edge-diag-ratio 1.75 "
         "--quad-max-normal-angle 10 --quad-max-interior-angle 135 --particle-aabb-min -1 -1 -1 --particle-aabb-max 9 9 9 "
         "--check-mesh=on --check-mesh-closed=on --check-mesh-manifold=on --check-mesh-orientation=on "
         "--check-mesh-debug=off --output-raw-mesh=off -v -o quads.ply", "quads.ply"),
        ("convert --particles canyon_13353401_particles.xyz -o converted.vtk --overwrite --domain-min -1 -1 -1 "
         "--domain-max 9 9 9", "converted.vtk"),
        ("convert --mesh quads.ply -o quads.obj", "quads.obj"),
    ]:
        result = subprocess.run([cli, *line.split()], capture_output=True, text=True, cwd=tmp_path)
        assert result.returncode == 0, f"{line}\n{result.stderr}"
        assert (tmp_path / output).stat().st_size > 10000, output


def test_frames_in_parallel_give_the_same_meshes(cli, shared, tmp_path):
    frames = tmp_path / "frames"
    frames.mkdir()
    for number in (30, 31, 32):
        shutil.copy(shared / f"sequence/double_dam_break_{number:04d}.vtk", frames / f"fluid_{number}.vtk")
    common = ["-r", "0.025", "-c", "1.0", "-q"]
    serial = run(cli, "reconstruct", frames / "fluid_{}.vtk", "-o", tmp_path / "a_{}.ply", *common)
    parallel = run(cli, "reconstruct", frames / "fluid_{}.vtk", "-o", tmp_path / "b_{}.ply", "--mt-files=on",
                   "--mt-particles=off", "--stats", tmp_path / "stats.json", *common)
    assert serial.returncode == 0 and parallel.returncode == 0, serial.stderr + parallel.stderr
    report = json.loads((tmp_path / "stats.json").read_text())
    assert report["parameters"]["frames_in_parallel"] == 2 and [f["frame"] for f in report["frames"]] == [30, 31, 32]
    for number in (30, 31, 32):
        assert (tmp_path / f"a_{number}.ply").read_bytes() == (tmp_path / f"b_{number}.ply").read_bytes()


def test_convert_keeps_particles_and_attributes_and_drops_those_outside_the_domain(cli, shared, tmp_path):
    source = shared / "splashsurf/bunny_frame_14_7705_particles.vtk"
    original = meniscus.read_particles(source)
    for extension in ("vtk", "ply"):
        out = tmp_path / f"all.{extension}"
        assert run(cli, "convert", "--particles", source, "-o", out).returncode == 0
        back = meniscus.read_particles(out)
        assert (back.positions == original.positions).all()
        assert set(back.attributes) == set(original.attributes)
        for name, values in original.attributes.items():
            assert (back.attributes[name] == values).all(), name
    out = tmp_path / "all.xyz"
    assert run(cli, "convert", "--particles", source, "-o", out).returncode == 0
    assert (meniscus.read_particles(out).positions == original.positions).all()
    # The domain: the lower half in x, bounds included; the same count as numpy's.
    middle = float(np.median(original.positions[:, 0]))
    result = run(cli, "convert", "--particles", source, "-o", tmp_path / "half.vtk", "--domain-min", -10, -10, -10,
                 "--domain-max", middle, 10, 10)
    assert result.returncode == 0, result.stderr
    inside = original.positions[:, 0] <= np.float32(middle)
    half = meniscus.read_particles(tmp_path / "half.vtk")
    assert len(half.positions) == inside.sum() and (half.positions == original.positions[inside]).all()
    assert f"{(~inside).sum()} outside the domain dropped" in result.stdout
    # An existing output is not replaced without --overwrite; a reversed box is named.
    refused = run(cli, "convert", "--particles", source, "-o", tmp_path / "half.vtk")
    assert refused.returncode != 0 and "--overwrite" in refused.stderr
    reversed_box = run(cli, "convert", "--particles", source, "-o", tmp_path / "r.vtk", "--domain-min", 1, 0, 0,
                       "--domain-max", 0, 1, 1)
    assert reversed_box.returncode != 0 and "--domain-min must be below --domain-max" in reversed_box.stderr


def test_quads_are_written_as_four_corner_faces_and_the_mesh_checks_closed(cli, shared, tmp_path):
    out = tmp_path / "quads.obj"
    stats = tmp_path / "stats.json"
    result = run(cli, "reconstruct", shared / "splashsurf/bunny_frame_14_7705_particles.vtk", "-r", 0.025, "-c", 0.75,
                 "--generate-quads", "--check-mesh", "--stats", stats, "-o", out, "-q")
    assert result.returncode == 0, result.stderr
    frame = json.loads(stats.read_text())["frames"][0]
    quads = sum(1 for line in out.read_text().splitlines() if line.startswith("f ") and len(line.split()) == 5)
    assert quads == frame["counts"]["quads"] > 1000
    assert frame["check"]["ok"]
