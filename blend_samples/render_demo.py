"""Renders the demo scene as an animation: every bundled frame, through Blender's own animation render.

    blender -b --factory-startup --python-exit-code 1 --python blend_samples/render_demo.py -- \
        --addon-path build/addon --frames 20 39 --output-dir build/demo/frames [--samples 16] [--motion-blur]

Unlike build_demo_scene.py (one still frame), this goes through the path users take with F12 > Render Animation:
the frame handler runs inside the render job for every frame, with the interface locked. With --motion-blur the
shutter subframes exercise the handler's "nothing changed" shortcut and Cycles reads the `velocity` attribute.
Prints the written PNG paths, one a line.
"""
import argparse
import os
import pathlib
import sys
import time

import bpy

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import build_demo_scene  # noqa: E402  (the scene itself; its main() runs only when it is the script)


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--addon-path", default=str(HERE.parent / "build" / "addon"))
    parser.add_argument("--frames", type=int, nargs=2, default=(20, 39), metavar=("FIRST", "LAST"))
    parser.add_argument("--output-dir", default=str(HERE.parent / "build" / "demo" / "frames"))
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--resolution", type=int, nargs=2, default=(640, 360), metavar=("WIDTH", "HEIGHT"))
    parser.add_argument("--motion-blur", action="store_true", help="render with motion blur (velocity attribute)")
    return parser.parse_args(argv)


def main():
    arguments = parse_arguments()
    scene, surface = build_demo_scene.build_scene(arguments.addon_path, arguments.samples, arguments.resolution)
    scene.frame_start, scene.frame_end = arguments.frames
    scene.render.use_motion_blur = arguments.motion_blur
    output_dir = os.path.abspath(arguments.output_dir)
    os.makedirs(output_dir, exist_ok=True)
    scene.render.filepath = os.path.join(output_dir, "frame_####")
    scene.render.use_file_extension = True

    started = time.perf_counter()
    bpy.ops.render.render(animation=True)
    elapsed = time.perf_counter() - started

    written = [scene.render.frame_path(frame=frame) for frame in range(scene.frame_start, scene.frame_end + 1)]
    missing = [path for path in written if not os.path.isfile(path)]
    if missing:
        raise RuntimeError(f"{len(missing)} frames were not written, first {missing[0]}")
    if surface.meniscus.status_is_error:
        raise RuntimeError(f"surface error during the render: {surface.meniscus.status}")
    print(f"rendered {len(written)} frames in {elapsed:.1f} s")
    for path in written:
        print(path)


main()
