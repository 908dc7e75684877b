"""Shared helpers of the headless Blender tests (not a test itself: the runners only run test_*.py).

Each test script runs in its own process, either inside a Blender executable or as plain Python with the `bpy`
module from PyPI (tests/blender/run_all.sh and run_bpy.sh):
    blender -b --factory-startup --python-exit-code 1 --python tests/blender/test_x.py -- --addon-path build/addon
    build/venv-bpy/bin/python tests/blender/test_x.py -- --addon-path build/addon
It runs its test_* functions in order and prints one line per test and a summary. Inside Blender a failure raises
at the end, which --python-exit-code turns into exit status 1. As a bpy module the process ends with os._exit:
some bpy wheels crash while tearing down at interpreter exit, after every result was printed, which would turn a
pass into a crash; the verdict is decided before that and flushed first.
"""
import argparse
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


def script_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--addon-path", default=str(REPO / "build" / "addon"),
                        help="folder that contains the staged 'meniscus' package")
    return parser.parse_args(argv)


def import_addon(addon_path=None):
    """Imports the staged package (not registered yet)."""
    addon_path = os.path.abspath(addon_path or script_arguments().addon_path)
    if not os.path.isdir(os.path.join(addon_path, "meniscus")):
        raise FileNotFoundError(f"no 'meniscus' package in {addon_path}")
    if addon_path not in sys.path:
        sys.path.insert(0, addon_path)
    import meniscus

    # Make sure we test the staged copy, not some other install that happens to be on the path.
    assert os.path.dirname(os.path.dirname(os.path.abspath(meniscus.__file__))) == addon_path, meniscus.__file__
    return meniscus


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
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(1 if failures else 0)
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
