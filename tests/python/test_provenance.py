"""Nothing stale, nothing silent (issue 32): every mesh carries what it was made from, and every consumer checks it;
frame ranges are bounded before anything is allocated; farm jobs say what they will redo or that they cannot run."""
import json
import os
import resource
import subprocess
import time

import pytest

from meniscus import cache, farm, sequence

from farm_support import PIPELINE, environment, make_sequence, python_command

FAST = ["-c", "1.0", "--threads", "1"]


def run(*command, timeout=300, **kwargs):
    return subprocess.run([str(c) for c in command], capture_output=True, text=True, timeout=timeout, **kwargs)


def outputs(folder):
    return {p.name: p.stat().st_mtime_ns for p in sorted(folder.glob("surface_*.ply"))}


def triangles(path):
    return len(cache.load_mesh(str(path)).triangles)


# ---- item 4: --skip-existing skips only what was made with the same parameters and input -------------------------

def test_skip_existing_redoes_outputs_of_other_parameters_or_inputs(cli, tmp_path):
    inputs = make_sequence(tmp_path / "in")
    out = tmp_path / "out"
    base = [cli, "reconstruct", inputs, "-o", out / "surface_{}.ply", "--frames", "1-3", *FAST, "--skip-existing"]
    assert run(*base, "-r", "0.025").returncode == 0
    first = outputs(out)
    before = triangles(out / "surface_0002.ply")
    assert len(first) == 3 and all((out / (name + ".meniscus")).is_file() for name in first)

    again = run(*base, "-r", "0.025")
    assert again.returncode == 0 and "3 of 3 frames skipped" in again.stderr and outputs(out) == first

    # Another radius: every frame is redone, saying why, and the meshes are those of the new radius.
    stats = tmp_path / "stats.json"
    changed = run(*base, "-r", "0.03", "-q", "--stats", stats)
    assert changed.returncode == 0, changed.stderr
    assert "3 of 3 frames redone" in changed.stderr
    assert "surface_0002.ply: made with particle_radius 0.025, now 0.03" in changed.stderr
    assert all(outputs(out)[name] != mtime for name, mtime in first.items())
    assert triangles(out / "surface_0002.ply") != before
    report = json.loads(stats.read_text())
    assert report["redone_frames"] == 3 and all("redone" in frame for frame in report["frames"])

    # A particle file rewritten since (new time), and an output without its record: those two only.
    current = outputs(out)
    os.utime(tmp_path / "in" / "fluid_0001.vtk", ns=(time.time_ns(), time.time_ns()))
    (out / "surface_0003.ply.meniscus").unlink()
    partly = run(*base, "-r", "0.03")
    assert partly.returncode == 0, partly.stderr
    assert "fluid_0001.vtk changed since" in partly.stderr and "surface_0003.ply: no record" in partly.stderr
    assert "1 of 3 frames skipped" in partly.stderr and "2 of 3 frames redone" in partly.stderr
    now = outputs(out)
    assert now["surface_0002.ply"] == current["surface_0002.ply"]
    assert now["surface_0001.ply"] != current["surface_0001.ply"] and now["surface_0003.ply"] != current["surface_0003.ply"]


def test_a_bake_job_records_provenance_and_names_what_a_cancel_left(tmp_path):
    """The add-on's bake (bpy-free part): each frame's record, and a cancelled re-bake names the frames it left."""
    inputs = make_sequence(tmp_path / "in")
    pattern = sequence.parse_pattern(str(inputs))
    frames = pattern.list_frames()
    target = str(tmp_path / "cache" / "fluid_{:04d}.npz")
    tasks = [cache.BakeTask(f, frames[f], target.format(f)) for f in (1, 2, 3, 4)]
    old = {"particle_radius": 0.025, "cube_size": 1.0, "threads": 1}
    cache.BakeJob(tasks, old).run()
    record = cache.provenance(frames[2], old)
    assert cache.stale_reason(target.format(2), record) == ""

    new = {**old, "particle_radius": 0.03}
    job = cache.BakeJob(tasks, new, on_frame=lambda job, task, result: job.cancel())
    job.run()
    assert job.cancelled and job.completed == 1
    assert cache.stale_reason(target.format(1), cache.provenance(frames[1], new)) == ""
    stale = job.stale_frames()
    assert sorted(stale) == [2, 3, 4] and stale[2] == "made with particle_radius 0.025, now 0.03"
    # Without the particle file, the parameters alone are checked.
    assert cache.stale_reason(target.format(3), cache.provenance(None, new)) == stale[3]
    assert cache.stale_reason(target.format(3), cache.provenance(None, old)) == ""
    # The thread count does not shape the mesh, nor does a parameter that takes no part (quad limits without
    # quads, by the schema's depends_on): no rebuild for them.
    assert cache.stale_reason(target.format(1), cache.provenance(frames[1], {**new, "threads": 2})) == ""
    unused = {**new, "quad_max_normal_angle": 20.0}
    assert cache.stale_reason(target.format(1), cache.provenance(frames[1], unused)) == ""
    assert cache.stale_reason(target.format(1), cache.provenance(frames[1], {**unused, "generate_quads": True})) == \
        "made with generate_quads 0, now 1"


# ---- item 4: a re-exported farm job says what it will redo, and redoes it -------------------------------------------

def export(tmp_path, inputs, radius, first=1, last=6):
    return run(*python_command(), "farm", "openjd", inputs, "-o", tmp_path / "out" / "surface_{}.ply", "-s", first,
               "-e", last, "-r", radius, *FAST, "--bundle", tmp_path / "bundle", env=environment())


def test_reexported_openjd_job_redoes_frames_of_other_parameters(cli, tmp_path):
    inputs = make_sequence(tmp_path / "in")
    exported = export(tmp_path, inputs, 0.025)
    assert exported.returncode == 0 and "redone" not in exported.stdout, exported.stdout + exported.stderr
    # Every task's command (template.yaml) on frames 1-6: what `openjd run` runs, without the runner.
    task = [cli, "reconstruct", "--parameters", tmp_path / "bundle" / "parameters.json", "--frames", "1-6",
            "--skip-existing", "-q"]
    assert run(*task).returncode == 0
    first = outputs(tmp_path / "out")
    before = triangles(tmp_path / "out" / "surface_0004.ply")

    again = export(tmp_path, inputs, 0.03)
    assert again.returncode == 0, again.stderr
    assert "6 frames will be redone" in again.stdout and "made with particle_radius 0.025, now 0.03" in again.stdout
    rerun = run(*task)
    assert rerun.returncode == 0 and "6 of 6 frames redone" in rerun.stderr, rerun.stderr
    assert all(outputs(tmp_path / "out")[name] != mtime for name, mtime in first.items())
    assert triangles(tmp_path / "out" / "surface_0004.ply") != before


def test_dask_chunk_redoes_stale_frames_and_reports_them(tmp_path):
    inputs = make_sequence(tmp_path / "in")
    output = str(tmp_path / "out" / "surface_{}.ply")
    text = farm.parameters_file_text({"particle_radius": 0.025, "cube_size": 1.0, "threads": 1}, str(inputs), output, 1, 2)
    assert all("skipped" not in r for r in farm._reconstruct_chunk(text, 1, 2, True))
    assert all("skipped" in r for r in farm._reconstruct_chunk(text, 1, 2, True))
    other = farm.parameters_file_text({"particle_radius": 0.03, "cube_size": 1.0, "threads": 1}, str(inputs), output, 1, 2)
    survey = farm.survey_outputs(json.loads(other), 1, 2)
    assert survey.frames == [1, 2] and sorted(survey.stale) == [1, 2] and not survey.missing
    records = farm._reconstruct_chunk(other, 1, 2, True)
    assert [r.get("redone") for r in records] == ["made with particle_radius 0.025, now 0.03"] * 2


# ---- item 8: a farm job over frames that do not exist --------------------------------------------------------------

def test_openjd_export_refuses_frames_that_do_not_exist_and_warns_of_gaps(tmp_path):
    inputs = make_sequence(tmp_path / "in")
    none = export(tmp_path, inputs, 0.025, 100, 120)
    assert none.returncode == 2 and "no particle files match" in none.stderr and "100-120" in none.stderr
    assert not (tmp_path / "bundle" / "template.yaml").exists()
    (tmp_path / "in" / "fluid_0003.vtk").unlink()
    gaps = export(tmp_path, inputs, 0.025, 1, 8)
    assert gaps.returncode == 0, gaps.stderr
    assert "warning: 3 frames have no particle file and will fail: 3, 7-8" in gaps.stdout


# ---- item 7: frame ranges bounded before anything is allocated -----------------------------------------------------

def _limited(limit_bytes=1 << 30):
    """A child that may not use more than 1 GiB: an unbounded range would fail by memory, not by our message."""
    return lambda: resource.setrlimit(resource.RLIMIT_AS, (limit_bytes, limit_bytes))


@pytest.mark.parametrize("end, words", [
    ("9223372036854775807", "end: must be a frame number from -999999999 to 999999999, got 9223372036854775807"),
    ("18446744073709551615", "end: must be a frame number from -999999999 to 999999999, got 18446744073709551615"),
    ("-9223372036854775808", "end: must be a frame number from -999999999 to 999999999, got -9223372036854775808"),
    ("500000", "end: frames 1-500000 are 500000 frames, more than the 100000 one run takes"),
])
def test_parameters_file_frame_range_is_bounded(cli, tmp_path, end, words):
    inputs = make_sequence(tmp_path / "in")
    parameters = tmp_path / "run.json"
    parameters.write_text('{"meniscus_parameters": 1, "input": %s, "output": %s, "start": 1, "end": %s, '
                          '"parameters": {"particle_radius": 0.025}}'
                          % (json.dumps(str(inputs)), json.dumps(str(tmp_path / "o_{}.ply")), end))
    started = time.monotonic()
    result = subprocess.run([cli, "reconstruct", "--parameters", str(parameters)], capture_output=True, text=True,
                            timeout=60, preexec_fn=_limited())
    assert result.returncode == 2 and words in result.stderr and str(parameters) in result.stderr, result.stderr
    assert time.monotonic() - started < 10


@pytest.mark.parametrize("flags, words", [
    (["-s", "0", "-e", "9223372036854775807"], "--end-index: must be a frame number from -999999999 to 999999999, "
                                               "got 9223372036854775807"),
    (["-s", "0", "-e", "18446744073709551615"], "--end-index: must be a frame number from -999999999 to 999999999, "
                                                "got 18446744073709551615"),
    (["-s", "-99999999999999999999", "-e", "1"], "--start-index: must be a frame number"),
    (["--frames", "1-99999999999999999999"], "--frames 1-99999999999999999999: 99999999999999999999 is not a frame "
                                             "number from -999999999 to 999999999"),
    (["--frames", "0-9223372036854775807"], "--frames 0-9223372036854775807: 9223372036854775807 is not a frame number"),
    (["-s", "1", "-e", "100001"], "frames 1-100001 are 100001 frames, more than the 100000 one run takes"),
])
def test_frame_range_flags_are_bounded(cli, tmp_path, flags, words):
    inputs = make_sequence(tmp_path / "in")
    result = subprocess.run([cli, "reconstruct", str(inputs), "-o", str(tmp_path / "o_{}.ply"), *PIPELINE, *flags],
                            capture_output=True, text=True, timeout=60, preexec_fn=_limited())
    assert result.returncode == 2 and words in result.stderr, result.stderr


def test_farm_export_refuses_an_unbounded_range(tmp_path):
    inputs = make_sequence(tmp_path / "in")
    result = export(tmp_path, inputs, 0.025, 0, 9223372036854775807)
    assert result.returncode == 2 and "must be a frame number" in result.stderr, result.stderr
    with pytest.raises(ValueError, match="end: .*must be a frame number.*got 18446744073709551615"):
        farm.parameters_file_text({"particle_radius": 0.025}, "in_{}.vtk", "out_{}.ply", 1, 18446744073709551615)


# ---- item 8: the bake's folder checks (bpy-free half; tests/blender/test_bake.py drives them through the add-on) -----

def test_killed_writers_temporary_files_are_removed_once_their_process_is_gone(tmp_path):
    dead = subprocess.Popen(["true"])
    dead.wait()
    left = [f"fluid_0023.partial{dead.pid}.npz", f".partial-{dead.pid}-surface_0023.ply"]
    kept = [f"fluid_0024.partial{os.getpid()}.npz", "fluid_0025.npz", "fluid_partial.npz"]
    recent = f"fluid_0026.partial{dead.pid}.npz"  # perhaps another machine's writer, at work: kept for now
    old = time.time() - cache.ABANDONED_AFTER_SECONDS - 60
    for name in left + kept + [recent]:
        (tmp_path / name).write_bytes(b"")
        if name != recent:
            os.utime(tmp_path / name, (old, old))
    assert sorted(cache.remove_abandoned_partials(str(tmp_path))) == sorted(left)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(kept + [recent])


def test_a_killed_farm_tasks_temporary_files_go_with_the_next_run_into_its_folder(cli, tmp_path):
    """A preempted farm task (SIGKILL mid-write) leaves its temporary mesh and record in the output folder: the next
    command-line run writing there removes them, and nothing of a live writer's."""
    inputs = make_sequence(tmp_path / "in")
    out = tmp_path / "out"
    out.mkdir()
    dead = subprocess.Popen(["true"])
    dead.wait()
    abandoned = [f".partial-{dead.pid}-surface_0002.ply", f"surface_0001.ply.partial{dead.pid}.meniscus"]
    live = f".partial-{os.getpid()}-surface_0003.ply"
    old = time.time() - cache.ABANDONED_AFTER_SECONDS - 60
    for name in abandoned + [live]:
        (out / name).write_bytes(b"ply\n")
        os.utime(out / name, (old, old))
    result = run(cli, "reconstruct", inputs, "-o", out / "surface_{}.ply", "--frames", "1-3", "-r", "0.025", *FAST)
    assert result.returncode == 0, result.stderr
    assert "removed 2 temporary files of killed runs in" in result.stderr, result.stderr
    assert sorted(p.name for p in out.iterdir()) == sorted(
        [live] + [f"surface_000{n}.ply" for n in (1, 2, 3)] + [f"surface_000{n}.ply.meniscus" for n in (1, 2, 3)])


def test_unwritable_cache_folder_is_named_before_any_work(tmp_path):
    (tmp_path / "a_file").write_text("not a folder")
    assert cache.writable_folder_problem(str(tmp_path / "a_file" / "cache")) == "Not a directory"
    assert cache.writable_folder_problem(str(tmp_path / "new" / "cache")) is None
    assert os.listdir(tmp_path / "new" / "cache") == []  # the probe is gone
