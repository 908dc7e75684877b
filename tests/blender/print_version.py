"""Prints the Blender version (for run.sh's log)."""
import os
import sys

import bpy

print("BLENDER_VERSION", bpy.app.version_string, flush=True)
if not bpy.app.binary_path:  # a bpy module: skip the teardown at exit (see _support.py)
    sys.stdout.flush()
    os._exit(0)
