"""Meniscus for Blender: fluid surfaces rebuilt from particle caches on every frame (View3D > Sidebar > Meniscus).

This package is the add-on only; the bpy-free library it drives (`api`, `cache`, `sequence` and the compiled core)
comes from one of two places:
- the extension zip (Blender 4.2+): Blender installs the bundled wheel that matches its Python as the top-level
  package `meniscus`, and this add-on runs as `bl_ext.<repository>.meniscus`;
- the legacy add-on zip (Blender 3.4-4.1): the library's modules sit next to this file (one compiled core per
  Python version), since those versions cannot install wheels.
"""
bl_info = {
    "name": "Meniscus",
    "author": "Meniscus developers",
    "version": (0, 2, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Meniscus",
    "description": "Smooth fluid surfaces from particle caches (SPH, FLIP), rebuilt on every frame",
    "doc_url": "",
    "category": "Import-Export",
}

import os  # noqa: E402
import sys  # noqa: E402



def _wait_briefly_at_barriers():
    """Sets the library's OpenMP wait policy (its waiting.py) before the core loads, which here happens below from
    its copy, before the library's __init__ would set it: GNU libgomp reads the policy only when it loads. The file
    is loaded by its path: importing the library package would load the core first."""
    import importlib.machinery
    import importlib.util

    path = os.path.join(os.path.dirname(__file__), "waiting.py")  # legacy zip: the library is bundled here
    if not os.path.exists(path):  # extension: in the wheel Blender installed (not a stale module of an old one)
        spec = importlib.machinery.PathFinder.find_spec("meniscus")
        if spec is None or not spec.origin:
            return
        path = os.path.join(os.path.dirname(spec.origin), "waiting.py")
        if not os.path.exists(path):  # an older library without it: its own __init__ sets the policy, or none does
            return
    spec = importlib.util.spec_from_file_location("_meniscus_waiting", path)
    waiting = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(waiting)
    waiting.wait_briefly_at_barriers()


_wait_briefly_at_barriers()

from . import core_copy  # noqa: E402


def _fresh_library(library):
    """Prepares the import of the library package `library` (this package or the wheel's `meniscus`): modules left
    by a previous install are dropped, so that an update runs its own code, and the core is loaded from a copy that
    the installer never overwrites (see core_copy)."""
    import importlib.util

    try:
        import bpy
    except ImportError:  # the legacy folder used as a plain Python library, outside Blender: nothing to update
        return
    for name in [name for name in sys.modules if name.startswith(library + ".") or
                 (name == library and library != __name__)]:
        if name != __name__ + ".core_copy":
            del sys.modules[name]
    spec = importlib.util.find_spec(library) if library != __name__ else None
    if library != __name__ and (spec is None or not spec.origin):  # no wheel installed: the import says so
        return
    package_dir = os.path.dirname(__file__ if spec is None else spec.origin)
    copies = bpy.utils.user_resource("DATAFILES", path=os.path.join("meniscus", "cores"), create=True)
    try:
        core_copy.load(library + "._core", package_dir, copies)
    except OSError as error:  # no writable folder: the core loads in place, as before
        print(f"Meniscus: loading the core in place ({error})")


if os.path.exists(os.path.join(os.path.dirname(__file__), "api.py")):  # legacy zip: the library is bundled here
    _fresh_library(__name__)
    from . import api, cache, parameters, sequence  # noqa: F401
    from . import farm, playback  # noqa: F401
    # Scripts in every Blender can then write `import meniscus; meniscus.reconstruct(...)`: here `meniscus` is this
    # add-on, in 4.2+ the library itself.
    from .api import *  # noqa: F401,F403
else:  # extension: the wheel Blender installed
    _fresh_library("meniscus")
    from meniscus import api, cache, parameters, sequence  # noqa: F401
    from meniscus import farm, playback  # noqa: F401


def register():
    from . import blender

    blender.register()


def unregister():
    from . import blender

    blender.unregister()
