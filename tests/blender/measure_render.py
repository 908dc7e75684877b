"""Measures an animation render with and without build-ahead (not a test: run by hand, prints figures), on an
installed add-on like the tests:
    MENISCUS_ADDON_KIND=extension MENISCUS_USER_DIR=<user dir> build/venv/bpy-5.2/bin/python \\
        tests/blender/measure_render.py -- FIRST LAST SAMPLES [WIDTH HEIGHT [RENDER_THREADS SURFACE_THREADS]]
Saves the sample sequence at the default render settings with a camera and a Cycles CPU render of SAMPLES samples
(RENDER_THREADS, SURFACE_THREADS: Cycles' and the surface's threads, 0 = all; one each stands in for a renderer that
leaves the CPU to the surface, as a GPU render does),
then renders frames FIRST..LAST in a new process each way, as a farm node does (`blender -b scene.blend -s -e -a`),
alternating the two three times, and reports each process's wall time and how many frames were built ahead."""
import os
import sys
import tempfile
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402

arguments = sys.argv[sys.argv.index("--") + 1:]
first, last, samples = int(arguments[0]), int(arguments[1]), int(arguments[2])
width, height = (int(arguments[3]), int(arguments[4])) if len(arguments) > 4 else (320, 180)
render_threads, surface_threads = (int(arguments[5]), int(arguments[6])) if len(arguments) > 6 else (0, 0)
addon = _support.enable_addon()
render_state = _support.addon_modules(addon, "blender.render_state")
_support.clear_scene()
scene = bpy.context.scene
surface = _support.add_sample_sequence()
folder = tempfile.mkdtemp(prefix="meniscus_measure_render_")
_support.make_small_render(scene, os.path.join(folder, "out", "frame_####"))
scene.cycles.samples = samples
scene.render.resolution_x, scene.render.resolution_y = width, height
if render_threads:
    scene.render.threads_mode, scene.render.threads = "FIXED", render_threads
if surface_threads:
    surface.meniscus.threads_auto, surface.meniscus.threads = False, surface_threads
blend = os.path.join(folder, "scene.blend")
bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True)
print(f"Blender {bpy.app.version_string}: frames {first}-{last}, Cycles CPU {samples} samples at {width}x{height}, "
      f"render cube size {surface.meniscus.render_cube_size}, smoothing {surface.meniscus.smoothing_iterations} "
      f"iterations, threads: Cycles {render_threads or 'all'}, surface {surface_threads or 'all'}")
for attempt in range(3):
    for build_ahead in (False, True):
        started = time.perf_counter()
        completed = _support.render_in_new_process(
            blend, first, last, report=f"bpy.data.objects[{surface.name!r}]", timeout=1800,
            environment={render_state.BUILD_AHEAD_VARIABLE: "1" if build_ahead else "0"})
        seconds = time.perf_counter() - started
        reports = [line for line in completed.stdout.splitlines() if line.startswith("RENDERED ")]
        ahead = sum("built ahead" in line for line in reports)
        print(f"build-ahead {'on ' if build_ahead else 'off'}: {seconds:.1f} s for {len(reports)} frames "
              f"({ahead} built ahead), exit status {completed.returncode}, load {os.getloadavg()[0]:.1f}")
        sys.stdout.flush()
addon.unregister()
os._exit(0)
