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
from . import waiting as _waiting

# Before the native module loads (with the api below): libgomp reads its wait policy only then.
_waiting.wait_briefly_at_barriers()

from .api import *  # noqa: E402,F401,F403  (the public API; its names are listed in api.__all__)
from .api import __all__  # noqa: F401
