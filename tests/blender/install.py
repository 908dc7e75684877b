"""Installs the add-on from a built zip the way a user does, into the fresh user folder run.sh made, and checks what
Blender installed. Run by tests/blender/run.sh before the test scripts, in the same Blender:
    <blender or bpy python> install.py -- ZIP extension|legacy

- extension (Blender 4.2+): Preferences > Get Extensions > Install from Disk, i.e.
  bpy.ops.extensions.package_install_files(repo="user_default", enable_on_install=True). Blender must pick the one
  bundled wheel built for its own Python and install nothing else.
- legacy (Blender 3.4-4.1): Preferences > Add-ons > Install, then the checkbox.
The preferences are saved with the add-on enabled, as Blender does on quit, so that a Blender started later
without --factory-startup (a render farm node) has it.
"""
import filecmp
import glob
import os
import sys
import sysconfig

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

arguments = sys.argv[sys.argv.index("--") + 1:]
ZIP, KIND = os.path.abspath(arguments[0]), arguments[1]
python_tag = f"cp{sys.version_info.major}{sys.version_info.minor}"
print("BLENDER_VERSION", bpy.app.version_string, flush=True)  # for run.sh's summary


def test_install_from_zip():
    if KIND == "extension":
        check(bpy.app.version >= (4, 2, 0), f"Blender {bpy.app.version_string} has no extensions: use the legacy zip")
        result = bpy.ops.extensions.package_install_files(filepath=ZIP, repo="user_default", enable_on_install=True)
    else:
        result = bpy.ops.preferences.addon_install(filepath=ZIP)
        check(result == {"FINISHED"}, f"addon_install: {result}")
        result = bpy.ops.preferences.addon_enable(module="meniscus")
    check(result == {"FINISHED"}, f"installing {ZIP}: {result}")
    enabled = {addon.module for addon in bpy.context.preferences.addons}
    check(_support.addon_module_name() in enabled, f"{_support.addon_module_name()} not enabled: {sorted(enabled)}")


def test_installed_where_a_user_install_goes():
    package = sys.modules[_support.addon_module_name()]
    user_dir = os.path.realpath(_support.USER_DIR)
    check(os.path.realpath(package.__file__).startswith(user_dir + os.sep), package.__file__)
    check(hasattr(bpy.types.Object, "meniscus") and hasattr(bpy.types, "MENISCUS_PT_main"), "add-on did not register")
    # The library the add-on drives: the wheel for this Python (extension) or the bundled modules (legacy).
    core = package.api._core
    check(os.path.realpath(core.__file__).startswith(user_dir + os.sep), core.__file__)
    check(os.path.basename(core.__file__).startswith(f"_core.{sysconfig.get_config_var('SOABI')}") or
          python_tag in os.path.basename(core.__file__), f"{core.__file__} is not built for {python_tag}")
    # It runs from its per-build copy (core_copy): a copy of the core the zip installed for this Python, beside the
    # library's modules (legacy: in the add-on's folder, among the cores of other Pythons; extension: the wheel's).
    installed_core = package.core_copy.core_file(os.path.dirname(package.api.__file__))
    check(installed_core is not None and filecmp.cmp(core.__file__, installed_core, shallow=False),
          f"the core loaded, {core.__file__}, is not the installed {installed_core}")
    if KIND == "extension":
        installed = glob.glob(os.path.join(user_dir, "extensions", ".local", "lib", "python*", "site-packages",
                                           "meniscus-*.dist-info"))
        check(len(installed) == 1, f"expected the one wheel for {python_tag}, found {installed}")
        cores = glob.glob(os.path.join(user_dir, "extensions", ".local", "lib", "python*", "site-packages",
                                       "meniscus", "_core.*"))
        # _core.cpython-311-x86_64-linux-gnu.so, _core.cp311-win_amd64.pyd
        check(len(cores) == 1 and python_tag in os.path.basename(cores[0]).replace("cpython-", "cp"), cores)


def test_preferences_saved():
    bpy.ops.wm.save_userpref()
    check(os.path.exists(os.path.join(_support.USER_DIR, "config", "userpref.blend")), "userpref.blend not written")


_support.run(globals())
