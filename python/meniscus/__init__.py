"""Meniscus: smooth, render-ready fluid surfaces from particle simulations (SPH, FLIP).

The bpy-free Python API over the native core; works in plain Python and inside Blender:

    import meniscus
    particles = meniscus.read_particles("fluid_0010.vtk")
    mesh = meniscus.reconstruct(particles.positions, particle_radius=0.025,
                                attributes={"velocity": particles.attributes["velocity"]})
    mesh.write("surface_0010.ply")

The command line is `meniscus` (or `python -m meniscus`). The Blender add-on is a separate package that uses this
one (installed from the extension zip, or bundled in the legacy add-on zip).
"""
import os as _os

# Threads waiting at OpenMP barriers spin briefly, then sleep, as in the CLI (native/core/base/waiting.h: the same
# values): GNU libgomp reads its policy only when it loads, with the native module imported below. A policy the user
# set stays as it is.
if "OMP_WAIT_POLICY" not in _os.environ:
    _os.environ.setdefault("GOMP_SPINCOUNT", "10000")
    _os.environ.setdefault("KMP_BLOCKTIME", "1")

from .api import *  # noqa: E402,F401,F403  (the public API; its names are listed in api.__all__)
from .api import __all__  # noqa: F401
