"""Shared helpers of the headless Blender tests (not a test itself: the runners only run test_*.py).

The tests run against the add-on as a user has it: tests/blender/run.sh installs a built zip into a fresh user
folder with install.py (the extension zip through Blender's extension installer on 4.2+, the legacy zip through the
add-on installer on 3.4) and then runs each test script in its own process, inside a Blender executable or as plain
Python with the `bpy` module from PyPI:
    tests/blender/run.sh /usr/bin/blender dist/meniscus-<version>-legacy-linux_x64.zip legacy
    tests/blender/run.sh build/venv/bpy-5.2/bin/python dist/meniscus-<version>-linux_x64.zip extension
A script enables the installed add-on (enable_addon) the way the Preferences checkbox does, then runs its test_*
functions in order and prints one line per test and a summary. Inside Blender a failure raises
at the end, which --python-exit-code turns into exit status 1. As a bpy module the process ends with exit_now:
some bpy wheels crash while tearing down at interpreter exit, after every result was printed, which would turn a
pass into a crash; the verdict is decided before that and flushed first. On Windows the process ends by
TerminateProcess, which skips the libraries' teardown as well: under Wine, bpy's DLL teardown after ExitProcess (where
Blender prints its leak report) can outlast Wine's grace for a terminating process, and Wine then kills it with
SIGKILL, a lost verdict (a CI run of the Windows bpy 4.5 suite, after every result of test_memory_release was printed).
"""
import importlib
import inspect
import os
import pathlib
import sys
import time
import traceback

import bpy
import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[2]
SAMPLE_DIR = REPO / "blend_samples" / "double_dam_break"
SAMPLE_PATTERN = str(SAMPLE_DIR / "double_dam_break_####.vtk")
SAMPLE_FIRST, SAMPLE_LAST = 20, 39
SAMPLE_RADIUS = 0.025
# The bpy module has no executable of its own; inside Blender binary_path names the blender program.
AS_MODULE = not bpy.app.binary_path

if AS_MODULE:
    # What --factory-startup does for the executable: no user preferences or startup file influence the tests.
    bpy.ops.wm.read_factory_settings(use_empty=False)


# The native command line of a build (MENISCUS_BUILD, else build/; tests/windows/run.sh names the mingw-w64 build).
COMMAND_LINE = os.path.join(os.environ.get("MENISCUS_BUILD", str(REPO / "build")), "bin",
                            "meniscus.exe" if os.name == "nt" else "meniscus")

# Set by run.sh: which package was installed, and the fresh user folder it was installed into.
ADDON_KIND = os.environ.get("MENISCUS_ADDON_KIND", "extension")
USER_DIR = os.environ.get("MENISCUS_USER_DIR", "")


def addon_module_name():
    """The add-on's module name: extensions live in the bl_ext namespace of their repository."""
    return "bl_ext.user_default.meniscus" if ADDON_KIND == "extension" else "meniscus"


def enable_addon():
    """Enables the installed add-on as the Preferences checkbox does and returns its package. Fails unless it is the
    copy run.sh installed into this run's user folder (never a source tree or a build folder)."""
    import addon_utils

    module = addon_utils.enable(addon_module_name(), default_set=True, handle_error=None)
    check(module is not None, f"Blender could not enable {addon_module_name()} (see the traceback above)")
    location = os.path.realpath(module.__file__)
    check(USER_DIR and location.startswith(os.path.realpath(USER_DIR) + os.sep),
          f"{addon_module_name()} was loaded from {location}, not from the installed copy in {USER_DIR!r}")
    return module


def addon_modules(addon, *names):
    """The add-on's submodules by dotted name relative to its package, e.g. addon_modules(addon, "blender.handlers")."""
    modules = [importlib.import_module(f"{addon.__name__}.{name}") for name in names]
    return modules[0] if len(modules) == 1 else modules


def clear_scene():
    """Removes the factory startup's cube, camera and light, and any data left by a previous test."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for collection in (bpy.data.meshes, bpy.data.materials, bpy.data.cameras, bpy.data.lights):
        for block in list(collection):
            collection.remove(block)


def add_sample_sequence(path=None, **options):
    """Runs the add operator like a script would; returns the new (active) surface object."""
    before = set(bpy.data.objects)
    result = bpy.ops.meniscus.add_sequence(filepath=path or str(SAMPLE_DIR / "double_dam_break_0020.vtk"),
                                           particle_radius=SAMPLE_RADIUS, **options)
    assert result == {"FINISHED"}, result
    added = [obj for obj in bpy.data.objects if obj not in before]
    assert len(added) == 1, added
    return added[0]


def failing_sequence(folder):
    """Copies sample frames 28, 29, 31 and 32 into folder/particles, 30 missing and 31 cut short in its point data
    (as an interrupted copy leaves it); returns (that folder, the path of the broken file)."""
    import shutil

    files = os.path.join(folder, "particles")
    os.makedirs(files)
    for frame in (28, 29, 31, 32):
        shutil.copy(SAMPLE_DIR / f"double_dam_break_00{frame}.vtk", files)
    broken = os.path.join(files, "double_dam_break_0031.vtk")
    with open(broken, "r+b") as handle:
        handle.truncate(4000)
    return files, broken


def make_small_render(scene, filepath=None):
    """A camera on the sample and the cheapest Cycles render that still runs every render handler (1 sample, 32 x 18
    pixels), writing PNGs to filepath when given."""
    import math

    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.location = (1.5, -3.5, 2.0)
    camera.rotation_euler = (math.radians(65), 0.0, 0.0)
    scene.camera = camera
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 32, 18, 100
    if filepath:
        scene.render.filepath = filepath
        scene.render.image_settings.file_format = "PNG"


def render_in_new_process(blend, first, last=None, report=None, timeout=180, environment=None):
    """Renders a saved .blend in a new process as a render farm node does: `blender -b scene.blend -f FIRST` (or
    -s FIRST -e LAST -a); as a bpy module, the same through bpy.ops.render.render(animation=True).
    The add-on comes from the saved preferences (the executable) or is enabled by name (a pipeline script on the
    module). report: an expression of an object whose first status line and face count are printed after each
    rendered frame, as 'RENDERED <status> <faces>'; environment: variables set for the process on top of this one's.
    Returns the CompletedProcess (stdout holds stderr too)."""
    import subprocess

    reporter = ""
    if report:  # registered after the file is open: loading a file drops handlers that are not persistent
        reporter = ("def _report(scene, *_args):\n"
                    f"    obj = {report}\n"
                    "    print('RENDERED', obj.meniscus.status.splitlines()[0], len(obj.data.polygons), flush=True)\n"
                    "bpy.app.handlers.render_post.append(_report)\n")
    if AS_MODULE:
        # Factory settings and the add-on by name (see test_bake); exit_now as in run(): the teardown may crash.
        opening = (f"import addon_utils, os\naddon_utils.enable({addon_module_name()!r}, default_set=True)\n"
                   f"bpy.ops.wm.open_mainfile(filepath={blend!r})\n")
        # An animation of one frame for a single frame: what -f does (a still would not number its file).
        render = (f"bpy.context.scene.frame_start, bpy.context.scene.frame_end = {first}, {first if last is None else last}\n"
                  "bpy.ops.render.render(animation=True)\n")
        code = "import bpy, sys\n" + opening + reporter + render + inspect.getsource(exit_now) + "exit_now(0)\n"
        command = [sys.executable, "-c", code]
    else:
        frames = ["-f", str(first)] if last is None else ["-s", str(first), "-e", str(last), "-a"]
        command = [bpy.app.binary_path, "-b", blend, "--python-expr", "import bpy, sys\n" + reporter] + frames
    return subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=timeout,
                          env=dict(os.environ, **(environment or {})))


def mantaflow_bake(name):
    """(folder, its scene.json) of a scene baked by tests/mantaflow/bake.sh into MENISCUS_BUILD (else build/), e.g.
    "pool_UNI"; bakes the scenes with Debian's Blender 3.4 when it is missing."""
    import json
    import subprocess

    build = pathlib.Path(os.environ.get("MENISCUS_BUILD", REPO / "build"))
    folder = build / "mantaflow" / name
    if not (folder / "scene.json").is_file():
        subprocess.run(["bash", str(REPO / "tests/mantaflow/bake.sh"), "/usr/bin/blender"], check=True,
                       env=dict(os.environ, MENISCUS_BUILD=str(build)))
    return folder, json.loads((folder / "scene.json").read_text())


def rebuilt_pool_domain(folder, frames, resolution):
    """The baked pool's liquid domain and obstacle (tests/mantaflow/bake_scene.py) rebuilt in a new scene saved in
    folder, its cache folder '//cache': the PyPI bpy modules cannot load Mantaflow caches, the add-on reads the files
    on its own. Returns (scene, domain)."""
    clear_scene()
    scene = bpy.context.scene
    bpy.ops.wm.save_as_mainfile(filepath=str(pathlib.Path(folder) / "module_scene.blend"))  # '//' resolves here
    scene.frame_start, scene.frame_end = 1, frames
    bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 0.75))
    domain = bpy.context.active_object
    domain.name, domain.scale = "Liquid Domain", (1, 1, 0.75)
    bpy.ops.mesh.primitive_cube_add(size=0.4, location=(0.5, 0.3, 0.25))
    obstacle = bpy.context.active_object
    obstacle.name = "Obstacle"
    obstacle.modifiers.new("Fluid", "FLUID").fluid_type = "EFFECTOR"
    modifier = domain.modifiers.new("Fluid", "FLUID")
    # The module's Mantaflow fails on any evaluation of a domain (and may abort the process): the add-on reads the
    # settings and the files, so the modifier may stay off.
    modifier.show_viewport = modifier.show_render = False
    modifier.fluid_type = "DOMAIN"
    settings = modifier.domain_settings
    settings.domain_type = "LIQUID"
    settings.cache_data_format, settings.cache_type = "UNI", "ALL"  # as baked (new 4.x domains: OpenVDB, Replay)
    settings.resolution_max = resolution
    settings.cache_frame_start, settings.cache_frame_end = 1, frames
    settings.cache_directory = "//cache"  # last: editing cache settings makes Blender delete the folder's files
    return scene, domain

def mesh_counts(obj):
    return len(obj.data.vertices), len(obj.data.polygons)


def connected_components(vertex_count, triangles):
    """Component label per vertex (label propagation with pointer jumping; numpy only, no scipy in Blender)."""
    labels = np.arange(vertex_count)
    while True:
        smallest = labels[triangles].min(axis=1)
        updated = labels.copy()
        for corner in range(3):
            np.minimum.at(updated, triangles[:, corner], smallest)
        while True:  # pointer jumping: follow labels to their roots, shortening long propagation chains
            jumped = updated[updated]
            if np.array_equal(jumped, updated):
                break
            updated = jumped
        if np.array_equal(updated, labels):
            return labels
        labels = updated


def check(condition, message):
    if not condition:
        raise AssertionError(message)


def exit_now(code):
    """Ends the process with code at once, after flushing the standard streams, skipping the interpreter's and the
    libraries' teardown (see the module's docstring): TerminateProcess on Windows, os._exit elsewhere."""
    import os, sys  # self-contained: render_blend sends this function's source to the processes it starts
    sys.stdout.flush()
    sys.stderr.flush()
    if os.name == "nt":
        import ctypes
        kernel32 = ctypes.windll.kernel32
        kernel32.GetCurrentProcess.restype = ctypes.c_void_p
        kernel32.TerminateProcess.argtypes = [ctypes.c_void_p, ctypes.c_uint]
        kernel32.TerminateProcess(kernel32.GetCurrentProcess(), code)
    os._exit(code)


def run(namespace, cleanup=None):
    """Runs the test_* functions of a module namespace in definition order, then cleanup(); fails the process if
    any test failed (raises inside Blender, exits with status 1 as a bpy module). Never returns as a module."""
    try:
        failures = _run_tests(namespace)
        if cleanup is not None:
            cleanup()
    except BaseException:
        traceback.print_exc()
        failures = ["(cleanup)"]
    if AS_MODULE:
        exit_now(1 if failures else 0)
    if failures:
        raise AssertionError("failed: " + ", ".join(failures))


def _run_tests(namespace):
    tests = [(name, value) for name, value in namespace.items() if name.startswith("test_") and callable(value)]
    failures = []
    for name, test in tests:
        started = time.perf_counter()
        try:
            test()
        except Exception:
            failures.append(name)
            print(f"FAIL {name}")
            traceback.print_exc()
        else:
            print(f"ok   {name} ({time.perf_counter() - started:.2f} s)")
        sys.stdout.flush()
    print(f"{len(tests) - len(failures)} passed, {len(failures)} failed")
    return failures
