"""Screenshot of the Meniscus N-panel with the demo scene (needs a display; under Xvfb for headless machines):

    blender -b --factory-startup --python blend_samples/build_demo_scene.py -- --save-blend /tmp/demo.blend --no-render
    xvfb-run -s '-screen 0 1280x720x24' blender --factory-startup /tmp/demo.blend \
        --python blend_samples/screenshot_npanel.py -- --addon-path build/addon --output docs/images/npanel.png

Opening a .blend on the command line keeps the splash screen away. Builds the demo scene, opens the sidebar on the Meniscus tab with the surface active, waits for the window to
draw, saves the screenshot and quits (exit status 1 when no screenshot was written).
"""
import argparse
import os
import pathlib
import sys

import bpy

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import build_demo_scene  # noqa: E402


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--addon-path", default=str(HERE.parent / "build" / "addon"))
    parser.add_argument("--output", default=str(HERE.parent / "docs" / "images" / "npanel.png"))
    return parser.parse_args(argv)


arguments = parse_arguments()
scene, surface = build_demo_scene.build_scene(arguments.addon_path, samples=8, resolution=(320, 180))
scene.frame_set(30)
bpy.context.view_layer.objects.active = surface
surface.select_set(True)
# Blender 3.4 cannot switch the sidebar's tab from Python (region.active_panel_category came later), so the
# other tabs' panels are unregistered in this throwaway session: Meniscus is then the only tab, and shown.
for panel in [getattr(bpy.types, name) for name in dir(bpy.types)]:
    if isinstance(panel, type) and issubclass(panel, bpy.types.Panel) and \
            getattr(panel, "bl_space_type", "") == "VIEW_3D" and getattr(panel, "bl_region_type", "") == "UI" and \
            getattr(panel, "bl_category", "") != "Meniscus" and "bl_rna" in panel.__dict__:
        try:
            bpy.utils.unregister_class(panel)
        except Exception:
            pass


def _view3d_areas():
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                yield window, area


def prepare_view():
    for _window, area in _view3d_areas():
        space = area.spaces.active
        space.show_region_ui = True
        space.shading.type = "SOLID"
        for region in area.regions:
            if region.type == "UI" and hasattr(region, "active_panel_category"):
                try:
                    region.active_panel_category = "Meniscus"
                except Exception:
                    pass
        # Frame the water: look at the surface from the camera.
        space.region_3d.view_perspective = "CAMERA"
    return None


steps = {"count": 0}


def take_screenshot():
    steps["count"] += 1
    if steps["count"] == 1:
        prepare_view()
        return 2.0  # let the sidebar draw (panels register their size on the first draw)
    output = os.path.abspath(arguments.output)
    os.makedirs(os.path.dirname(output), exist_ok=True)
    window = bpy.context.window_manager.windows[0]
    try:
        with bpy.context.temp_override(window=window, screen=window.screen):
            bpy.ops.screen.screenshot(filepath=output)
    except AttributeError:  # before 3.2: no temp_override
        bpy.ops.screen.screenshot({"window": window, "screen": window.screen}, filepath=output)
    print("screenshot:", output, os.path.isfile(output))
    sys.stdout.flush()
    os._exit(0 if os.path.isfile(output) else 1)


bpy.app.timers.register(take_screenshot, first_interval=3.0)
