"""Registration: register/unregister cycles, handlers installed exactly once, survival of file loads."""
import os
import pathlib
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import _support  # noqa: E402
from _support import check  # noqa: E402

addon = _support.enable_addon()
addon.unregister()  # the tests below register and unregister themselves


def count_ours(handler_list):
    return sum(1 for function in handler_list if getattr(function, "__module__", "").startswith(addon.__name__ + "."))


def operator_registered(idname):
    # bpy.ops.<module>.<name> always builds a wrapper, registered or not; its RNA type exists only when registered.
    try:
        return getattr(bpy.ops.meniscus, idname).get_rna_type().identifier == "MENISCUS_OT_" + idname
    except (KeyError, AttributeError):
        return False


def check_registered(expected):
    check(hasattr(bpy.types.Object, "meniscus") == expected, f"Object.meniscus registered should be {expected}")
    check(hasattr(bpy.types, "MENISCUS_OT_add_sequence") == expected, "operator registration")
    check(hasattr(bpy.types, "MENISCUS_PT_main") == expected, "panel registration")
    for idname in ("add_sequence", "bake"):
        check(operator_registered(idname) == expected, f"bpy.ops.meniscus.{idname} registered should be {expected}")
    count = 1 if expected else 0
    check(count_ours(bpy.app.handlers.frame_change_post) == count,
          f"frame_change_post holds {count_ours(bpy.app.handlers.frame_change_post)} Meniscus handlers, want {count}")
    for name in ("load_post", "undo_post", "redo_post"):
        check(count_ours(getattr(bpy.app.handlers, name)) == count, f"{name} handler count")


def test_register_unregister_twice():
    for _ in range(2):
        addon.register()
        check_registered(True)
        addon.unregister()
        check_registered(False)


def test_repeated_register_is_harmless():
    addon.register()
    addon.register()  # e.g. an add-on manager calling register again: must not duplicate handlers or raise
    check_registered(True)
    addon.unregister()
    addon.unregister()
    check_registered(False)


def test_handler_survives_file_load_and_relative_path_resolves():
    addon.register()
    try:
        _support.clear_scene()
        with tempfile.TemporaryDirectory() as folder:
            blend = os.path.join(folder, "scene.blend")
            bpy.ops.wm.save_as_mainfile(filepath=blend)  # saved first: relative paths need the .blend's folder
            obj = _support.add_sample_sequence(relative_path=True)
            stored = obj.meniscus.file_pattern
            check(stored.startswith("//"), f"path should be stored relative, got {stored!r}")
            check(stored.endswith("double_dam_break_####.vtk"), stored)
            check(pathlib.Path(bpy.path.abspath(stored)).resolve() == pathlib.Path(_support.SAMPLE_PATTERN).resolve(),
                  f"{stored!r} does not resolve to the sample")
            bpy.context.scene.frame_set(_support.SAMPLE_FIRST)
            check(len(obj.data.vertices) > 0, "surface empty before saving")
            bpy.ops.wm.save_mainfile()

            bpy.ops.wm.open_mainfile(filepath=blend)
            check_registered(True)  # load_post re-installed the frame handler exactly once
            surfaces = [o for o in bpy.data.objects if o.type == "MESH" and o.meniscus.is_surface]
            check(len(surfaces) == 1, f"expected one surface after reload, got {surfaces}")
            surface = surfaces[0]
            scene = bpy.context.scene
            scene.frame_set(_support.SAMPLE_FIRST + 5)
            check(len(surface.data.vertices) > 0 and not surface.meniscus.status_is_error,
                  f"surface did not rebuild after reload: {surface.meniscus.status!r}")
            check(surface.meniscus.status.startswith("double_dam_break_0025"), surface.meniscus.status)
    finally:
        addon.unregister()
    check_registered(False)


def test_enable_disable_through_addon_utils():
    # The path Blender's preferences take: addon_utils imports the package by name and calls register().
    import addon_utils

    name = _support.addon_module_name()
    module = addon_utils.enable(name, default_set=False, handle_error=None)
    check(module is addon, f"addon_utils could not enable {name}")
    check_registered(True)
    addon_utils.disable(name, default_set=False, handle_error=None)
    check_registered(False)


def test_frame_change_without_addon_is_inert():
    # After unregistering, changing frames must not touch the meshes (no stray handler left behind).
    bpy.ops.wm.read_homefile(use_empty=True)
    addon.register()
    obj = _support.add_sample_sequence()
    bpy.context.scene.frame_set(_support.SAMPLE_FIRST)
    vertices = len(obj.data.vertices)
    addon.unregister()
    bpy.context.scene.frame_set(_support.SAMPLE_FIRST + 7)
    check(len(obj.data.vertices) == vertices, "mesh changed after unregister")


_support.run(globals())
