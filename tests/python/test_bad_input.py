"""Bad input through the command-line tool: sequences with gaps, duplicate frame numbers and mixed formats, broken
and unreadable frames, non-finite coordinates and frames beyond the memory budget. The readers' own bad-input
matrix is in tests/native/test_bad_input.cpp; this checks what a render-farm user sees: the failing frame named,
the reason given, the other frames written, and the exit code telling that something failed."""
import json
import os
import pathlib
import shutil
import subprocess
import tempfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
FORMATS = ROOT / "tests" / "data" / "formats"
VARIANTS = FORMATS / "variants"


def run(cli, *args, **kwargs):
    return subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=600, **kwargs)


def reconstruct(cli, pattern, output, *extra, **kwargs):
    return run(cli, "reconstruct", pattern, "-o", output, "-r", 0.025, "-c", 1.0, "--threads", 2, "-q", *extra, **kwargs)


@pytest.fixture
def frames(tmp_path):
    folder = tmp_path / "in"
    folder.mkdir()
    return folder


def test_mixed_formats_in_one_sequence_are_read_by_content(cli, frames, tmp_path):
    # A cache folder whose files were renamed to one extension: every frame is recognised by its content.
    sources = ["binary.vtk", "raw_zlib_uint64_be.vtu", "binary.bgeo", "deflated.npz", "binary_le.ply", "positions.npy"]
    for n, name in enumerate(sources, start=1):
        shutil.copy(VARIANTS / name, frames / f"fluid_{n:04d}.dat")
    shutil.copy(FORMATS / "dam26.csv", frames / f"fluid_{len(sources) + 1:04d}.dat")
    stats = tmp_path / "stats.json"
    result = reconstruct(cli, frames / "fluid_{}.dat", tmp_path / "out_{}.ply", "--stats", stats)
    assert result.returncode == 0, result.stderr
    report = json.loads(stats.read_text())
    counts = [f["counts"]["particles"] for f in report["frames"]]
    assert counts == [5, 5, 5, 5, 5, 5, 4732]
    for n in range(1, len(sources) + 2):
        assert (tmp_path / f"out_{n:04d}.ply").stat().st_size > 0


def test_gaps_and_broken_frames_are_reported_and_skipped(cli, frames, tmp_path):
    shutil.copy(VARIANTS / "binary.vtk", frames / "fluid_1.vtu")            # legacy VTK under .vtu: read by content
    shutil.copy(VARIANTS / "raw_plain_uint32_le.vtu", frames / "fluid_2.vtu")
    (frames / "fluid_3.vtu").write_bytes(b"")                               # empty
    data = (VARIANTS / "raw_zlib_uint32_le.vtu").read_bytes()
    (frames / "fluid_4.vtu").write_bytes(data[: len(data) // 2])            # truncated
    (frames / "fluid_5.vtu").mkdir()                                        # a directory
    # frame 6 is missing
    shutil.copy(VARIANTS / "base64_zlib_uint32_le.vtu", frames / "fluid_7.vtu")
    stats = tmp_path / "stats.json"
    result = reconstruct(cli, frames / "fluid_{}.vtu", tmp_path / "out_{}.ply", "-s", 1, "-e", 7, "--stats", stats)
    assert result.returncode == 1
    assert "fluid_3.vtu: empty file" in result.stderr
    assert "fluid_4.vtu: truncated" in result.stderr
    assert "fluid_5.vtu: is a directory" in result.stderr
    assert "frame 6 is missing" in result.stderr
    assert "5 of 7 frames failed" not in result.stderr and "4 of 7 frames failed" in result.stderr
    report = json.loads(stats.read_text())
    assert [("failed" in f) for f in report["frames"]] == [False, False, True, True, True, True, False]
    assert sorted(p.name for p in tmp_path.glob("out_*.ply")) == ["out_1.ply", "out_2.ply", "out_7.ply"]


def test_duplicate_frame_numbers_use_one_file_deterministically(cli, frames, tmp_path):
    # fluid_7 and fluid_007 are both frame 7: the pattern's own spelling ({} is unpadded) is used, every time, as in the
    # Python API and the add-on (one rule, io/frame_pattern.h), with a warning naming both.
    shutil.copy(VARIANTS / "binary.bgeo", frames / "fluid_7.bgeo")
    shutil.copy(VARIANTS / "binary.bgeo", frames / "fluid_007.bgeo")
    shutil.copy(VARIANTS / "binary.bgeo", frames / "fluid_8.bgeo")
    stats = tmp_path / "stats.json"
    result = reconstruct(cli, frames / "fluid_{}.bgeo", tmp_path / "out_{}.ply", "--stats", stats)
    assert result.returncode == 0, result.stderr
    report = json.loads(stats.read_text())
    assert [f["frame"] for f in report["frames"]] == [7, 8]
    assert report["frames"][0]["input"].endswith("fluid_7.bgeo")
    assert "frame 7: fluid_007.bgeo and fluid_7.bgeo; using fluid_7.bgeo" in result.stderr
    assert sorted(p.name for p in tmp_path.glob("out_*.ply")) == ["out_7.ply", "out_8.ply"]


def test_non_finite_coordinates_fail_with_a_count_or_are_skipped(cli, tmp_path):
    frame = tmp_path / "nan.csv"
    rows = ["x,y,z"] + [f"{0.05 * (i % 5)},{0.05 * (i // 5 % 5)},{0.05 * (i // 25)}" for i in range(50)]
    frame.write_text("\n".join(rows + ["nan,0,0", "0,0,inf", "-inf,1,1"]) + "\n")
    result = reconstruct(cli, frame, tmp_path / "out.ply")
    assert result.returncode == 1
    assert "3 of 53 particles have NaN or Inf coordinates" in result.stderr and "--skip-invalid" in result.stderr
    assert not (tmp_path / "out.ply").exists()
    result = reconstruct(cli, frame, tmp_path / "out.ply", "--skip-invalid")
    assert result.returncode == 0, result.stderr
    assert "dropped 3 particles" in result.stderr
    assert (tmp_path / "out.ply").stat().st_size > 0


def test_far_coordinates_and_memory_budget_are_refused(cli, tmp_path):
    frame = tmp_path / "far.csv"
    frame.write_text("x,y,z\n0,0,0\n0.05,0,0\n1e30,0,0\n")
    result = reconstruct(cli, frame, tmp_path / "out.ply")
    assert result.returncode == 1 and "too large for the grid" in result.stderr

    result = run(cli, "reconstruct", FORMATS / "dam26_binary.ply", "-o", tmp_path / "out.ply", "-r", 0.025, "-c", 0.001, "-q")
    assert result.returncode == 1
    assert "would need about" in result.stderr and "memory budget" in result.stderr
    result = run(cli, "reconstruct", FORMATS / "dam26.npz", "-o", tmp_path / "out.ply", "-r", 0.025, "-c", 1.0, "-q",
                 "--memory-budget", 0.0001)
    assert result.returncode == 1 and "more than the memory budget" in result.stderr


def test_unreadable_files(cli, tmp_path):
    # The kernel refuses this read to everyone, root included.
    if os.path.exists("/proc/self/mem"):
        result = reconstruct(cli, "/proc/self/mem", tmp_path / "out.ply")
        assert result.returncode == 1 and "/proc/self/mem: read error" in result.stderr

    # chmod 000 stops everyone but root, whose reads bypass permissions: as root, run the tool as "nobody".
    folder = pathlib.Path(tempfile.mkdtemp(prefix="meniscus_unreadable_"))
    try:
        folder.chmod(0o777)
        frame = folder / "locked.vtu"
        shutil.copy(VARIANTS / "ascii.vtu", frame)
        frame.chmod(0)
        kwargs = {}
        if os.geteuid() == 0:
            if not os.access(cli, os.X_OK) or not all(os.stat(p).st_mode & 0o001 for p in pathlib.Path(cli).parents if p != p.parent):
                pytest.skip("the CLI is not reachable for an unprivileged user")
            kwargs = {"user": 65534, "group": 65534}
        result = reconstruct(cli, frame, folder / "out.ply", **kwargs)
        assert result.returncode == 1
        assert "locked.vtu: cannot open file: Permission denied" in result.stderr
    finally:
        shutil.rmtree(folder, ignore_errors=True)
