"""Screenshot of the Meniscus sidebar in a real Blender window (Xvfb), for the README: the sidebar alone, at its
default width.

    xvfb-run -s '-screen 0 1200x1500x24' blender -p 0 0 1200 1500 --factory-startup --python docs/screenshot_npanel.py -- \
        --addon-path build/addon --output docs/images/npanel.png

Blender 3.4 offers no way to pick the sidebar's open tab from Python, so for this picture only the Meniscus panels
are shown under the always-present "Item" tab (below its Transform panel); in use they have
their own "Meniscus" tab.
"""
import pathlib
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
addon_path = argv[argv.index("--addon-path") + 1] if "--addon-path" in argv else "build/addon"
output = pathlib.Path(argv[argv.index("--output") + 1] if "--output" in argv else "docs/images/npanel.png").resolve()
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "blend_samples"))
import build_demo_scene  # noqa: E402

bpy.context.preferences.view.show_splash = False
build_demo_scene.build_scene(addon_path, samples=8)
bpy.context.scene.frame_set(30)

from meniscus.blender import panels  # noqa: E402

main_panel = panels.MENISCUS_PT_main
children = [c for c in vars(panels).values() if isinstance(c, type) and issubclass(c, bpy.types.Panel) and c is not main_panel]
for cls in reversed([main_panel] + children):
    bpy.utils.unregister_class(cls)
main_panel.bl_order = -100  # above the Transform panel
for cls in [main_panel] + children:
    cls.bl_category = "Item"
    bpy.utils.register_class(cls)
# The Item tab's Properties panel is left out of the picture (Transform is drawn by Blender itself and stays).
properties_panel = getattr(bpy.types, "VIEW3D_PT_context_properties", None)
if properties_panel is not None:
    bpy.utils.unregister_class(properties_panel)


def view3d_area():
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                return window, area
    return None, None


def show_sidebar():
    window, area = view3d_area()
    if area is None:
        return 0.5
    space = area.spaces.active
    space.show_region_ui = True
    # The 3D view alone fills the window, so the sidebar gets its whole height.
    override = {"window": window, "screen": window.screen, "area": area}
    if hasattr(bpy.context, "temp_override"):
        with bpy.context.temp_override(**override):
            bpy.ops.screen.screen_full_area()
    else:
        bpy.ops.screen.screen_full_area(override)
    area.tag_redraw()
    bpy.app.timers.register(take_screenshot, first_interval=3.0)
    return None


def crop_to_sidebar(area):
    """Keeps only the sidebar (at Blender's default width), so that the picture is readable at its own size."""
    import numpy as np
    sidebar = next(region for region in area.regions if region.type == "UI")
    image = bpy.data.images.load(str(output))
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(height, width, 4)  # rows from the bottom, as window coordinates
    x0, y0 = sidebar.x, sidebar.y  # window coordinates, as the screenshot
    part = np.ascontiguousarray(pixels[y0:y0 + sidebar.height, x0:x0 + sidebar.width])
    cropped = bpy.data.images.new("npanel", sidebar.width, sidebar.height, alpha=True)
    cropped.pixels.foreach_set(part.ravel())
    cropped.filepath_raw = str(output)
    cropped.file_format = "PNG"
    cropped.save()


def take_screenshot():
    window, area = view3d_area()
    override = {"window": window, "screen": window.screen, "area": area}
    if hasattr(bpy.context, "temp_override"):
        with bpy.context.temp_override(**override):
            bpy.ops.screen.screenshot(filepath=str(output))
    else:
        bpy.ops.screen.screenshot(override, filepath=str(output))
    crop_to_sidebar(area)
    print("screenshot", output)
    bpy.ops.wm.quit_blender()
    return None


bpy.app.timers.register(show_sidebar, first_interval=2.0)
