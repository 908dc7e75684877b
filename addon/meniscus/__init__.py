"""Meniscus: smooth, render-ready fluid surfaces from particle simulations.

The package is both the Python API (``import meniscus``; no bpy needed) and the Blender add-on (``register`` /
``unregister``, imported lazily so that the API works outside Blender).
"""
bl_info = {
    "name": "Meniscus",
    "author": "Meniscus developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Meniscus",
    "description": "Smooth fluid surfaces from particle caches (SPH, FLIP), rebuilt on every frame",
    "category": "Import-Export",
}

from .api import (  # noqa: E402,F401
    FormatError,
    Mesh,
    Particles,
    __version__,
    assess_quality,
    check_mesh,
    read_mesh,
    read_particles,
    reconstruct,
    write_mesh,
)


def register():
    from . import blender

    blender.register()


def unregister():
    from . import blender

    blender.unregister()
