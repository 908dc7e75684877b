"""Safe updates: installing a zip over the enabled add-on never crashes Blender. The core runs from a per-build copy
that no installer writes to, so a core file rewritten in place (what Blender 3.4's installer does) leaves the running
one alone; a zip of a newer version installed over the enabled one runs its own code; the same zip again too.

Run: tests/blender/run.sh (installs the add-on from its zip first; see _support.py)
"""
import os
import re
import sys
import tempfile
import zipfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

arguments = sys.argv[sys.argv.index("--") + 1:]
ZIP, KIND = os.path.abspath(arguments[0]), arguments[1]
addon = _support.enable_addon()
_temporary = tempfile.TemporaryDirectory(prefix="meniscus_update_")
_support.clear_scene()
scene = bpy.context.scene


def installed_core():
    """The core file the installer wrote, beside the library's modules."""
    import importlib.machinery

    folder = os.path.dirname(addon.api.__file__)
    found = [os.path.join(folder, "_core" + suffix) for suffix in importlib.machinery.EXTENSION_SUFFIXES
             if os.path.isfile(os.path.join(folder, "_core" + suffix))]
    check(len(found) >= 1, f"no core for this Python in {folder}")
    return found[0]


def build_and_count(frame):
    scene.frame_set(frame)
    surface = bpy.data.objects.get("double_dam_break") or _support.add_sample_sequence()
    surface.meniscus.cube_size = 2.0
    surface.meniscus.smoothing_iterations = 0
    surface.meniscus.smoothing_reach = 0.0
    _support.addon_modules(sys.modules[_support.addon_module_name()], "blender.update").update_surface(
        surface, scene, force=True)
    check(not surface.meniscus.status_is_error and len(surface.data.polygons) > 0, surface.meniscus.status)
    return len(surface.data.polygons)


def test_the_core_runs_from_a_copy_outside_the_installed_files():
    running = os.path.realpath(addon.api._core.__file__)
    check(running != os.path.realpath(installed_core()), f"the core runs from the installed file {running}")
    check(running.startswith(os.path.realpath(_support.USER_DIR) + os.sep) and
          f"{os.sep}meniscus{os.sep}cores{os.sep}" in running, running)


def test_a_core_rewritten_in_place_does_not_crash_the_running_one():
    before = build_and_count(30)
    path = installed_core()
    with open(path, "rb") as stream:
        original = stream.read()
    try:
        with open(path, "r+b") as stream:  # in place, same inode: what 3.4's installer does to a mapped library
            stream.write(b"\0" * len(original))
        bpy.data.objects.remove(bpy.data.objects["double_dam_break"])
        check(build_and_count(31) > 0 and build_and_count(30) == before, "rebuilt differently")
    finally:
        with open(path, "r+b") as stream:
            stream.write(original)


def _newer_zip():
    """The tested zip with its version raised (bl_info and the extension manifest), as the next release."""
    newer = os.path.join(_temporary.name, os.path.basename(ZIP).replace(".zip", "-next.zip"))
    with zipfile.ZipFile(ZIP) as source, zipfile.ZipFile(newer, "w", zipfile.ZIP_DEFLATED) as target:
        for item in source.infolist():
            data = source.read(item)
            if item.filename.endswith("blender_manifest.toml"):
                data = re.sub(rb'^version = "[^"]*"', b'version = "9.9.9"', data, flags=re.M)
            elif item.filename in ("meniscus/__init__.py", "__init__.py"):  # legacy, extension
                data = re.sub(rb'"version": \([^)]*\)', b'"version": (9, 9, 9)', data)
                data += b"\nTEST_BUILD = 'next'  # which code runs after the update\n"
            target.writestr(item, data)
    return newer


def _install(path):
    if KIND == "extension":
        result = bpy.ops.extensions.package_install_files(filepath=path, repo="user_default", enable_on_install=True)
    else:
        result = bpy.ops.preferences.addon_install(filepath=path, overwrite=True)
        check(result == {"FINISHED"}, result)
        result = bpy.ops.preferences.addon_enable(module="meniscus")
    check(result == {"FINISHED"}, f"installing {path}: {result}")
    return sys.modules[_support.addon_module_name()]


def test_a_newer_zip_over_the_enabled_add_on_then_the_same_again():
    before = build_and_count(30)
    updated = _install(_newer_zip())
    check(getattr(updated, "TEST_BUILD", None) == "next", "the code of the previous install still runs")
    check(build_and_count(31) > 0 and build_and_count(30) == before, "the updated add-on builds differently")
    restored = _install(ZIP)  # the tested zip again (the later test scripts use it)
    # (A reloaded module keeps the names its previous code set, so the installed file tells which zip is in place.)
    with open(restored.__file__) as installed:
        check("TEST_BUILD" not in installed.read(), "the reinstalled zip did not replace the newer one")
    check(build_and_count(30) == before, "after reinstalling")


_support.run(globals())
