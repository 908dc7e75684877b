"""Loads the compiled core from a copy of its own, one folder per build, which no installer ever writes to.

Installing a zip over an enabled add-on replaces the files of the core that Blender has loaded: Blender 3.4's
installer rewrites them in place (the mapped library changes under the running code: a crash), and pip (4.2+) puts
a new library at the same path, where the dynamic loader hands back the old one still mapped (the new Python code
would run on the old core). A copy in a folder named by the core's content hash avoids both: a new build loads from
a new path, a rewrite never touches a mapped file, and the same build reuses its copy.

Windows locks a loaded library against writes and deletion: loaded in place, an installer could not replace it at
all (the update would fail); the copy is what stays locked, and a copy that another Blender still runs is left for
a later start to remove.
"""
import hashlib
import importlib.machinery
import importlib.util
import os
import shutil
import sys

from . import busy_files

# Libraries the wheel tools vendor beside the core: auditwheel in ../<package>.libs (reached through the core's run
# path $ORIGIN/../<package>.libs), delocate in .dylibs; the legacy zip puts them beside the core ($ORIGIN).
_LIBRARY_PREFIXES = ("lib",)


def core_file(package_dir):
    """The core built for this Python in package_dir, or None."""
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = os.path.join(package_dir, "_core" + suffix)
        if os.path.isfile(path):
            return path
    return None


def _digest(path):
    hasher = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            hasher.update(block)
    return hasher.hexdigest()[:16]


def _copy_build(source, package_dir, target):
    """Copies the core and its vendored libraries into target, in the layout their run paths expect."""
    package = os.path.join(target, os.path.basename(package_dir))
    os.makedirs(package)
    shutil.copy2(source, package)
    for name in os.listdir(package_dir):
        if name.startswith(_LIBRARY_PREFIXES) and ".so" in name:
            shutil.copy2(os.path.join(package_dir, name), package)
    dylibs = os.path.join(package_dir, ".dylibs")
    if os.path.isdir(dylibs):
        shutil.copytree(dylibs, os.path.join(package, ".dylibs"))
    wheel_libraries = os.path.join(os.path.dirname(package_dir), os.path.basename(package_dir) + ".libs")
    if os.path.isdir(wheel_libraries):
        shutil.copytree(wheel_libraries, os.path.join(target, os.path.basename(wheel_libraries)))


def load(module_name, package_dir, copies_root):
    """Loads the core of package_dir as module_name (e.g. 'meniscus._core') from its copy under copies_root and
    puts it into sys.modules, where the package's `from . import _core` finds it. Returns the path loaded, or None
    when nothing was done (no core there): the ordinary import then loads it in place."""
    source = core_file(package_dir)
    if source is None:
        return None
    target = os.path.join(copies_root, _digest(source))
    copied = os.path.join(target, os.path.basename(package_dir), os.path.basename(source))
    if not os.path.isfile(copied):
        staging = f"{target}.partial-{os.getpid()}"
        shutil.rmtree(staging, ignore_errors=True)
        _copy_build(source, package_dir, staging)
        try:
            # Whole or not at all. Another Blender may have put the same build there first: the rename over its
            # folder is refused, and its copy serves. On Windows a virus scanner may still be reading the new core,
            # which refuses the rename for a moment.
            busy_files.replace(staging, target, otherwise=lambda: os.path.isfile(copied))
        except OSError as error:
            if not os.path.isfile(copied):
                raise OSError(f"the copy of the core could not be moved into place at {target} "
                              f"({error.strerror or error})") from error
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    spec = importlib.util.spec_from_file_location(module_name, copied)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[module_name] = module
    _remove_other_builds(copies_root, keep=os.path.basename(target))
    return copied


def _remove_other_builds(copies_root, keep):
    # Copies of other builds: a Blender still running an older one keeps its mapping (unlinking never changes a
    # mapped file), so they can go now; on Windows its loaded copy cannot, and stays until a later start.
    for name in os.listdir(copies_root):
        if name != keep and ".partial-" not in name:
            shutil.rmtree(os.path.join(copies_root, name), ignore_errors=True)
