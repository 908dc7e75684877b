"""The installed add-on surfaces a frame, then is removed as a user removes it, and nothing of it stays: the add-on
folder is gone and nothing is registered. On Windows, which deletes no loaded library, the removal of the enabled
add-on works because its core runs from the per-build copy (core_copy), not from the folder removed.

Not one of the suite's test_*.py scripts (it ends the installed add-on): run.sh runs it when named, after install.py,
    MENISCUS_BLENDER_SCRIPTS=uninstall tests/blender/run.sh BLENDER ZIP legacy|extension
(tests/windows/run.sh: the legacy Windows zip in Windows bpy 4.5).
- legacy: Preferences > Add-ons > Remove, i.e. bpy.ops.preferences.addon_remove, on the enabled add-on;
- extension: Get Extensions > Uninstall, i.e. bpy.ops.extensions.package_uninstall.
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
_support.clear_scene()
scene = bpy.context.scene


def test_a_frame_surfaces():
    surface = _support.add_sample_sequence()
    scene.frame_set(30)
    check(not surface.meniscus.status_is_error and len(surface.data.polygons) > 0, surface.meniscus.status)
    check(surface.data.attributes.get("velocity") is not None, sorted(surface.data.attributes.keys()))


def test_removed_while_enabled():
    folder = os.path.dirname(addon.__file__)
    if _support.ADDON_KIND == "legacy":
        try:
            result = bpy.ops.preferences.addon_remove(module=_support.addon_module_name())
        except RuntimeError as error:
            # The operator's last step redraws the Preferences area, which a Blender without a window has not; the
            # removal is done by then (checked below).
            check("tag_redraw" in str(error), str(error))
            result = {"FINISHED"}
    else:
        result = bpy.ops.extensions.package_uninstall(repo_index=_user_repository_index(), pkg_id="meniscus")
    check(result == {"FINISHED"}, f"removing the add-on: {result}")
    left = os.listdir(folder) if os.path.exists(folder) else []
    check(not left and not os.path.exists(folder), f"the add-on folder {folder} stays, with {left}")
    enabled = {module.module for module in bpy.context.preferences.addons}
    check(_support.addon_module_name() not in enabled, f"still enabled: {sorted(enabled)}")
    check(not hasattr(bpy.types, "MENISCUS_PT_main"), "its panel is still registered")


def _user_repository_index():
    repositories = bpy.context.preferences.extensions.repos
    return next(index for index, repository in enumerate(repositories) if repository.module == "user_default")


_support.run(globals())
