"""Tests of meniscus.sequence: frame patterns, folder listings (the core's rule, shared with the CLI) and scene frame
resolution (no bpy)."""
import importlib.util
import os
import pathlib
import sys

import pytest

from meniscus import sequence  # noqa: E402

FramePattern = sequence.FramePattern
parse_pattern = sequence.parse_pattern
resolve_file_frame = sequence.resolve_file_frame


def touch(directory, *names):
    for name in names:
        (directory / name).write_bytes(b"")


# --- pattern detection -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name, prefix, padding, suffix", [
    ("fluid_0001.bgeo", "fluid_", 4, ".bgeo"),
    ("fluid_0001.bgeo.gz", "fluid_", 4, ".bgeo.gz"),
    ("ParticleData_Fluid_5.vtk", "ParticleData_Fluid_", 0, ".vtk"),
    ("double_dam_break_0020.vtk", "double_dam_break_", 4, ".vtk"),
    ("run2_fluid_007.vtk", "run2_fluid_", 3, ".vtk"),      # digits in the prefix are not the frame number
    ("fluid_0001_surface.vtk", "fluid_", 4, "_surface.vtk"),
    ("frame12.h5", "frame", 0, ".h5"),                      # the '5' of '.h5' is part of the extension
    ("0042.vtk", "", 4, ".vtk"),
    ("fluid_0.vtk", "fluid_", 0, ".vtk"),                   # a lone zero is not padding
    ("fluid_####.bgeo", "fluid_", 4, ".bgeo"),
    ("fluid_######.vtk", "fluid_", 6, ".vtk"),
    ("fluid_{}.vtk", "fluid_", 0, ".vtk"),
    ("{}.xyz", "", 0, ".xyz"),
])
def test_parse_pattern(name, prefix, padding, suffix):
    pattern = parse_pattern(os.path.join("some", "dir", name), sibling_names=[])
    assert (pattern.prefix, pattern.padding, pattern.suffix) == (prefix, padding, suffix)
    assert pattern.directory == os.path.join("some", "dir")


def test_parse_pattern_keeps_blender_relative_prefix():
    # Blender-relative paths ('//') must survive untouched: the add-on resolves them with bpy.path.abspath later.
    pattern = parse_pattern("//cache/fluid_####.vtk")
    assert pattern.directory == "//cache"
    assert pattern.pattern_string() == "//cache/fluid_####.vtk"


@pytest.mark.parametrize("name", ["fluid.vtk", "README", "fluid_##_##.vtk", "a{}b{}.vtk"])
def test_parse_pattern_rejects_names_without_one_frame_number(name):
    with pytest.raises(ValueError):
        parse_pattern(name, sibling_names=[])


def test_parse_pattern_rejects_folder():
    with pytest.raises(ValueError):
        parse_pattern("some/dir/")


def test_ambiguous_padding_is_settled_by_siblings():
    # 'fluid_10' has no leading zero: padded to two digits only if a sibling shows one.
    assert parse_pattern("fluid_10.vtk", sibling_names=["fluid_09.vtk", "fluid_10.vtk"]).padding == 2
    assert parse_pattern("fluid_10.vtk", sibling_names=["fluid_9.vtk", "fluid_10.vtk"]).padding == 0
    # Siblings of another sequence do not count.
    assert parse_pattern("fluid_10.vtk", sibling_names=["other_09.vtk", "fluid_09.bgeo"]).padding == 0


def test_ambiguous_padding_reads_the_folder(tmp_path):
    touch(tmp_path, "fluid_098.vtk", "fluid_099.vtk", "fluid_100.vtk")
    assert parse_pattern(str(tmp_path / "fluid_100.vtk")).padding == 3


def test_pattern_string_round_trip():
    for text in ["d/fluid_####.vtk", "d/fluid_{}.vtk"]:
        assert parse_pattern(text).pattern_string() == text
    assert parse_pattern("d/fluid_0001.vtk").pattern_string() == "d/fluid_####.vtk"
    assert parse_pattern("d/fluid_1.vtk", sibling_names=[]).pattern_string() == "d/fluid_{}.vtk"


def test_file_name_formatting():
    assert FramePattern("d", "fluid_", ".vtk", 4).file_name(7) == "fluid_0007.vtk"
    assert FramePattern("d", "fluid_", ".vtk", 4).file_name(12345) == "fluid_12345.vtk"  # longer than the padding
    assert FramePattern("d", "fluid_", ".vtk", 0).file_name(7) == "fluid_7.vtk"
    assert FramePattern("d", "fluid_", ".vtk", 4).path(7) == os.path.join("d", "fluid_0007.vtk")


def test_match():
    pattern = FramePattern("d", "fluid_", ".vtk", 4)
    assert pattern.match("fluid_0007.vtk") == (7, "0007")
    assert pattern.match("fluid_7.vtk") == (7, "7")
    for other in ["fluid_.vtk", "fluid_0007.vtk.bak", "fluid_00a7.vtk", "fluid_-1.vtk", "fluid_٣.vtk", "gas_0007.vtk"]:
        assert pattern.match(other) is None, other


# --- folder listing ----------------------------------------------------------------------------------------------

def test_list_frames_padded(tmp_path):
    touch(tmp_path, "fluid_0003.vtk", "fluid_0001.vtk", "fluid_0002.vtk", "fluid_0002.vtk.tmp", "other_0001.vtk",
          "fluid_0001.bgeo", "notes.txt")
    frames = parse_pattern(str(tmp_path / "fluid_0001.vtk")).list_frames()
    assert list(frames) == [1, 2, 3]  # sorted by frame
    assert frames[2] == str(tmp_path / "fluid_0002.vtk")


def test_list_frames_unpadded_sorts_numerically(tmp_path):
    touch(tmp_path, *[f"ParticleData_Fluid_{i}.vtk" for i in (0, 1, 2, 10, 11, 100)])
    frames = parse_pattern(str(tmp_path / "ParticleData_Fluid_5.vtk")).list_frames()
    assert list(frames) == [0, 1, 2, 10, 11, 100]
    assert frames[10] == str(tmp_path / "ParticleData_Fluid_10.vtk")


def test_list_frames_tolerates_mixed_spellings(tmp_path):
    # A padded sequence that outgrew its padding, plus a duplicate spelling of frame 7.
    touch(tmp_path, "fluid_0007.vtk", "fluid_7.vtk", "fluid_9999.vtk", "fluid_10000.vtk")
    frames = FramePattern(str(tmp_path), "fluid_", ".vtk", 4).list_frames()
    assert list(frames) == [7, 9999, 10000]
    assert frames[7].endswith("fluid_0007.vtk")  # the spelling matching the padding wins
    assert FramePattern(str(tmp_path), "fluid_", ".vtk", 0).list_frames()[7].endswith("fluid_7.vtk")


def test_list_frames_of_missing_folder_is_empty(tmp_path):
    assert FramePattern(str(tmp_path / "nowhere"), "fluid_", ".vtk", 4).list_frames() == {}


def test_bundled_sample_sequence():
    folder = pathlib.Path(__file__).resolve().parents[2] / "blend_samples" / "double_dam_break"
    if not folder.is_dir():
        pytest.skip("bundled sample not present")
    frames = parse_pattern(str(folder / "double_dam_break_####.vtk")).list_frames()
    assert sequence.frame_range(frames) == (20, 39)
    assert len(frames) == 20


# --- scene frame -> file frame -----------------------------------------------------------------------------------

def test_resolve_inside_range_applies_offset():
    assert resolve_file_frame(30, 0, 20, 39, "HOLD") == 30
    assert resolve_file_frame(1, 19, 20, 39, "BLANK") == 20
    assert resolve_file_frame(50, -20, 20, 39, "LOOP") == 30


def test_resolve_hold():
    assert resolve_file_frame(5, 0, 20, 39, "HOLD") == 20
    assert resolve_file_frame(100, 0, 20, 39, "HOLD") == 39


def test_resolve_loop():
    # 20 frames repeat: 40 -> 20, 59 -> 39, 60 -> 20, and before the start 19 -> 39, 0 -> 20.
    assert [resolve_file_frame(f, 0, 20, 39, "LOOP") for f in (40, 59, 60, 19, 0, -1)] == [20, 39, 20, 39, 20, 39]
    assert resolve_file_frame(7, 0, 3, 3, "LOOP") == 3  # a single-frame range


def test_resolve_blank():
    assert resolve_file_frame(19, 0, 20, 39, "BLANK") is None
    assert resolve_file_frame(40, 0, 20, 39, "BLANK") is None
    assert resolve_file_frame(39, 0, 20, 39, "BLANK") == 39


def test_subframes_resolve_to_the_nearest_frame():
    # Motion blur shutter steps around frame 30 must all show file 30.
    assert [resolve_file_frame(t, 0, 20, 39, "HOLD") for t in (29.75, 30.0, 30.25, 30.49)] == [30, 30, 30, 30]
    assert resolve_file_frame(30.5, 0, 20, 39, "HOLD") == 31
    assert sequence.nearest_frame(-0.5) == 0 and sequence.nearest_frame(-0.51) == -1


def test_resolve_rejects_bad_input():
    with pytest.raises(ValueError):
        resolve_file_frame(1, 0, 10, 5, "HOLD")
    with pytest.raises(ValueError):
        resolve_file_frame(1, 0, 0, 5, "CLAMP")


def test_lookup_frame_reports_missing_file(tmp_path):
    touch(tmp_path, "f_0001.vtk", "f_0003.vtk")
    pattern = FramePattern(str(tmp_path), "f_", ".vtk", 4)
    frames = pattern.list_frames()
    found = sequence.lookup_frame(frames, pattern, 3, 0, 1, 3, "HOLD")
    assert found.file_frame == 3 and found.path == str(tmp_path / "f_0003.vtk")
    gap = sequence.lookup_frame(frames, pattern, 2, 0, 1, 3, "HOLD")
    assert gap.file_frame == 2 and gap.path is None and gap.expected_path == str(tmp_path / "f_0002.vtk")
    blank = sequence.lookup_frame(frames, pattern, 9, 0, 1, 3, "BLANK")
    assert blank.file_frame is None and blank.path is None


# --- cache -------------------------------------------------------------------------------------------------------

def test_cache_rescans_when_folder_changes(tmp_path):
    touch(tmp_path, "f_0001.vtk")
    cache = sequence.SequenceCache()
    pattern = cache.pattern(str(tmp_path / "f_####.vtk"))
    assert cache.pattern(str(tmp_path / "f_####.vtk")) is pattern  # parsed once
    assert list(cache.frames(pattern)) == [1]
    touch(tmp_path, "f_0002.vtk")
    # Some filesystems have coarse timestamps: force a visible change of the folder's mtime.
    stat = os.stat(tmp_path)
    os.utime(tmp_path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 1_000_000_000))
    assert list(cache.frames(pattern)) == [1, 2]
    cache.clear()
    assert list(cache.frames(cache.pattern(str(tmp_path / "f_####.vtk")))) == [1, 2]


def test_frame_range():
    assert sequence.frame_range({}) is None
    assert sequence.frame_range({5: "a", 2: "b", 9: "c"}) == (2, 9)
