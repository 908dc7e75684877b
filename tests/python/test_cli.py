"""The command-line tool: single frames, sequences with gaps and broken frames, stats, output formats."""
import json
import pathlib
import shutil
import subprocess

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
