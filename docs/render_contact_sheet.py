"""Renders a short animation strip of the bundled demo (blend_samples/) and tiles it into one contact sheet PNG.

    blender -b --factory-startup --python-exit-code 1 --python docs/render_contact_sheet.py -- \
        --addon-path build/addon --output docs/images/contact_sheet.png

Builds the demo scene with blend_samples/build_demo_scene.py, renders frames 20, 24, 28, 32, 36, 39 with Cycles
(320x180, 16 samples, no denoising), and tiles them 3 columns x 2 rows with numpy and Blender's image API (no PIL).
"""
import argparse
import os
import pathlib
import sys
import tempfile
import time

import bpy
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "blend_samples"))
import build_demo_scene  # noqa: E402


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--addon-path", default=str(ROOT / "build" / "addon"))
    parser.add_argument("--output", default=str(ROOT / "docs" / "images" / "contact_sheet.png"))
    parser.add_argument("--frames", type=int, nargs="+", default=[20, 24, 28, 32, 36, 39])
    parser.add_argument("--columns", type=int, default=3)
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--resolution", type=int, nargs=2, default=(320, 180), metavar=("WIDTH", "HEIGHT"))
    parser.add_argument("--gap", type=int, default=4, help="white pixels between tiles")
    return parser.parse_args(argv)


def load_pixels(path, width, height):
    """(height, width, 4) float32 RGBA, top row first (Blender's pixel buffers start at the bottom row)."""
    image = bpy.data.images.load(path)
    try:
        pixels = np.empty(width * height * 4, dtype=np.float32)
        image.pixels.foreach_get(pixels)
    finally:
        bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)[::-1]


def write_png(canvas, path):
    """Writes a (H, W, 4) top-row-first float RGBA array through a byte image (values stored as they are)."""
    height, width = canvas.shape[:2]
    image = bpy.data.images.new("contact_sheet", width, height, alpha=False)
    image.pixels.foreach_set(np.ascontiguousarray(canvas[::-1], dtype=np.float32).reshape(-1))
    image.filepath_raw = path
    image.file_format = "PNG"
    image.save()
    bpy.data.images.remove(image)


def main():
    arguments = parse_arguments()
    width, height = arguments.resolution
    scene, surface = build_demo_scene.build_scene(arguments.addon_path, arguments.samples, (width, height))
    scene.cycles.use_denoising = False

    tiles = []
    with tempfile.TemporaryDirectory() as folder:
        for frame in arguments.frames:
            scene.frame_set(frame)
            if surface.meniscus.status_is_error or len(surface.data.polygons) == 0:
                raise RuntimeError(f"no surface at frame {frame}: {surface.meniscus.status}")
            path = os.path.join(folder, f"frame_{frame:04d}.png")
            scene.render.filepath = path
            started = time.perf_counter()
            bpy.ops.render.render(write_still=True)
            print(f"frame {frame}: {len(surface.data.polygons)} triangles, rendered in "
                  f"{time.perf_counter() - started:.1f} s")
            sys.stdout.flush()
            tiles.append(load_pixels(path, width, height))

    columns = arguments.columns
    rows = (len(tiles) + columns - 1) // columns
    gap = arguments.gap
    canvas = np.ones((rows * height + (rows + 1) * gap, columns * width + (columns + 1) * gap, 4), dtype=np.float32)
    for index, tile in enumerate(tiles):
        row, column = divmod(index, columns)
        top, left = gap + row * (height + gap), gap + column * (width + gap)
        canvas[top:top + height, left:left + width] = tile
    canvas[..., 3] = 1.0

    output = os.path.abspath(arguments.output)
    os.makedirs(os.path.dirname(output), exist_ok=True)
    write_png(canvas, output)
    if not os.path.isfile(output):
        raise RuntimeError(f"could not write {output}")
    print(output)


main()
