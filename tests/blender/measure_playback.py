"""Measures viewport playback (not a test: run by hand, prints figures), on an installed add-on like the tests:
    MENISCUS_ADDON_KIND=extension MENISCUS_USER_DIR=<user dir> build/venv/bpy-5.2/bin/python \
        tests/blender/measure_playback.py -- ../shared/data/sequence/double_dam_break_0000.vtk 0.5 [no-normals]
Adds the sequence at the default viewport settings (no-normals: Custom Normals off), shows its first frame, then steps one frame every PACE seconds
(the time Blender would spend drawing and waiting) and reports how many frame changes found their mesh ready in
memory and what each frame change cost on Blender's thread."""
import os
import statistics
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402

arguments = sys.argv[sys.argv.index("--") + 1:]
first_file, pace = os.path.abspath(arguments[0]), float(arguments[1])
custom_normals = "no-normals" not in arguments[2:]
addon = _support.enable_addon()
mesh_update, update = _support.addon_modules(addon, "blender.mesh_update", "blender.update")
# Seconds of each frame change spent in the mesh write and, within it, in the custom normals (Blender's thread).
spent = {"write_surface": [], "_write_custom_normals": []}


def _timed(name):
    original = getattr(mesh_update, name)

    def call(*args, **kwargs):
        started = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            spent[name].append(time.perf_counter() - started)
    setattr(mesh_update, name, call)


for _name in spent:
    _timed(_name)
_support.clear_scene()
scene = bpy.context.scene
obj = _support.add_sample_sequence(first_file)
obj.meniscus.use_custom_normals = custom_normals
first, last = obj.meniscus.frame_start, obj.meniscus.frame_end
costs, ready = [], []
started = time.perf_counter()
scene.frame_set(first)
print(f"first frame {first}: {time.perf_counter() - started:.3f} s; {obj.meniscus.status.splitlines()[1:3]}")
for frame in range(first + 1, last + 1):
    time.sleep(pace)
    started = time.perf_counter()
    scene.frame_set(frame)
    costs.append(time.perf_counter() - started)
    ready.append("ready in memory" in obj.meniscus.status)
fast = [cost for cost in costs if cost <= 0.05]
print(f"custom normals {'on' if custom_normals else 'off'}; {len(costs)} frame changes at a {pace} s pace: {sum(ready)} ready in memory ({100 * sum(ready) / len(costs):.0f} %), "
      f"{len(fast)} cost <= 0.05 s ({100 * len(fast) / len(costs):.0f} %); cost median {statistics.median(costs):.3f} s, "
      f"ready median {statistics.median([c for c, r in zip(costs, ready) if r] or [0]):.3f} s, max {max(costs):.3f} s")
kept = update._memory.frames.get(obj.data.as_pointer())
builds = [entry[0].seconds for entry in kept._entries.values()] if kept is not None else []
if builds:  # reading and reconstructing, by the worker or Blender's thread (the frames still in memory)
    print(f"build per frame: median {statistics.median(builds):.2f} s, max {max(builds):.2f} s over {len(builds)} kept frames")
for name, seconds in spent.items():
    if seconds:
        print(f"{name}: median {statistics.median(seconds[1:] or seconds):.3f} s over {len(seconds)} calls")
sys.stdout.flush()
addon.unregister()
os._exit(0)
