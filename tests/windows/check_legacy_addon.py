"""Runs inside a Windows CPython under Wine (started by tests/windows/test_wheels.py --legacy-zip) on the legacy add-on
folder, the Blender 3.4-4.1 zip unpacked, used as a plain library as a pipeline script outside Blender may use it:

    python.exe check_legacy_addon.py FOLDER FRAME OUTPUT_DIR

- Its compiled core for this Python is the one imported, from FOLDER/meniscus, and reconstructs the particle file
  FRAME at radius 0.025 into OUTPUT_DIR/legacy.ply (test_wheels.py compares it with the Linux mesh).
- The add-on's replacement of a file or folder another program holds open without delete sharing (its busy_files,
  behind the Alembic export, the failed frame's image and the core's copy): Windows refuses the rename until the
  program lets go, so it is waited for; when it never lets go, the error names the file and the time waited. Python's
  own open() shares no delete access, so it plays the other program. Wine refuses these renames as Windows does; a
  folder whose file is open it renames, unlike Windows, so the core's copy is held by a handle on the folder itself
  (as a file manager window or a scanner may hold it).
Exits non-zero with the reason on the first failure.
"""
import ctypes
import importlib.machinery
import os
import pathlib
import shutil
import sys
import threading
import time
from ctypes import wintypes

HELD_SECONDS = 1.0  # how long the other program holds a file in the cases where it lets go
SHORT_WAIT_SECONDS = 0.5  # busy_files.WAIT_SECONDS in the cases where it never lets go (5 s in the add-on)


def fail(message):
    print(f"FAILED: {message}", flush=True)
    sys.exit(1)


def timed(function, *arguments, **keywords):
    """(seconds taken, the exception raised or None)."""
    started = time.monotonic()
    try:
        function(*arguments, **keywords)
    except Exception as error:  # noqa: BLE001 (the caller checks which)
        return time.monotonic() - started, error
    return time.monotonic() - started, None


def hold_folder(path):
    """Opens the folder as a file manager or scanner may, sharing read and write but not delete; returns a function
    that closes it."""
    kernel32 = ctypes.WinDLL("kernel32", use_last_error=True)
    kernel32.CreateFileW.restype = wintypes.HANDLE
    kernel32.CreateFileW.argtypes = [wintypes.LPCWSTR, wintypes.DWORD, wintypes.DWORD, ctypes.c_void_p,
                                     wintypes.DWORD, wintypes.DWORD, wintypes.HANDLE]
    generic_read, share_read_write, open_existing, backup_semantics = 0x80000000, 0x1 | 0x2, 3, 0x02000000
    handle = kernel32.CreateFileW(str(path), generic_read, share_read_write, None, open_existing, backup_semantics,
                                  None)
    if handle in (None, wintypes.HANDLE(-1).value):
        fail(f"could not open the folder {path}: error {ctypes.get_last_error()}")
    return lambda: kernel32.CloseHandle(handle)


def check_core(meniscus, folder, frame, out):
    tag = f"cp{sys.version_info.major}{sys.version_info.minor}"
    core = sys.modules["meniscus._core"].__file__
    expected = folder / "meniscus" / f"_core.{tag}-win_amd64.pyd"
    if pathlib.Path(meniscus.__file__).resolve().parent != (folder / "meniscus").resolve():
        fail(f"meniscus was imported from {meniscus.__file__}, not from the legacy add-on folder {folder}")
    if pathlib.Path(core).resolve() != expected.resolve():
        fail(f"the core loaded is {core}, not the legacy zip's {expected.name} for {tag}")
    particles = meniscus.read_particles(frame)
    mesh = meniscus.reconstruct(particles.positions, 0.025)
    meniscus.write_mesh(mesh, out / "legacy.ply")
    print(f"legacy add-on as a library: {expected.name} loaded from the add-on folder; {len(mesh.triangles)} "
          "triangles")


def check_busy_files(busy_files, out):
    folder = out / "busy files"
    folder.mkdir()
    source, target = folder / "new.abc", folder / "played.abc"

    # The target held open by a reader that lets go after a moment: replaced once it does.
    source.write_bytes(b"new"), target.write_bytes(b"old")
    with open(target, "rb") as reader:
        threading.Timer(HELD_SECONDS, reader.close).start()
        seconds, error = timed(busy_files.replace, source, target)
    if error is not None or target.read_bytes() != b"new" or source.exists():
        fail(f"a target held open for {HELD_SECONDS:g} s: {error!r}, target {target.read_bytes()!r}")
    if not HELD_SECONDS * 0.8 <= seconds < busy_files.WAIT_SECONDS:
        fail(f"a target held open for {HELD_SECONDS:g} s was replaced after {seconds:.2f} s")
    print(f"a target held open for {HELD_SECONDS:g} s: replaced after {seconds:.2f} s")

    # The file to rename held open (the failed frame's image in a viewer), then let go: renamed.
    image, renamed = folder / "frame_0030.png", folder / "frame_0030.meniscus-failed.png"
    image.write_bytes(b"rendered without the surface")
    with open(image, "rb") as viewer:
        threading.Timer(HELD_SECONDS, viewer.close).start()
        seconds, error = timed(busy_files.replace, image, renamed)
    if error is not None or image.exists() or not renamed.exists() or seconds < HELD_SECONDS * 0.8:
        fail(f"a file held open for {HELD_SECONDS:g} s, renamed: {error!r} after {seconds:.2f} s")
    print(f"a file held open for {HELD_SECONDS:g} s: renamed after {seconds:.2f} s")

    # Never let go: refused after the wait, naming the file and the time waited; nothing changed.
    source.write_bytes(b"newer")
    busy_files.WAIT_SECONDS = SHORT_WAIT_SECONDS
    with open(target, "rb"):
        seconds, error = timed(busy_files.replace, source, target)
    if not isinstance(error, busy_files.StillHeldOpen) or str(target) not in str(error) or \
            f"waited {SHORT_WAIT_SECONDS:g} s" not in str(error):
        fail(f"a target held open throughout: {error!r}")
    if seconds < SHORT_WAIT_SECONDS or target.read_bytes() != b"new" or source.read_bytes() != b"newer":
        fail(f"a target held open throughout: refused after {seconds:.2f} s, target {target.read_bytes()!r}")
    print(f"a target held open throughout: refused after {seconds:.2f} s ({error})")


def check_core_copy(core_copy, busy_files, folder, out):
    """The core's copy (what the add-on loads in Blender) put into place while another program holds its new
    folder, and when the same build's copy is already there (another Blender was first)."""
    package = folder / "meniscus"
    copy_build = core_copy._copy_build

    def copy_and_hold(seconds):
        def copy(source, package_dir, staging):
            copy_build(source, package_dir, staging)
            release = hold_folder(staging)
            if seconds is not None:
                threading.Timer(seconds, release).start()
            holders.append(release)
        return copy

    holders = []
    busy_files.WAIT_SECONDS = 5.0
    core_copy._copy_build = copy_and_hold(HELD_SECONDS)
    try:
        seconds, error = timed(core_copy.load, "held_copy._core", str(package), str(out / "cores held"))
    finally:
        core_copy._copy_build = copy_build
    loaded = sys.modules.get("held_copy._core")
    if error is not None or loaded is None or seconds < HELD_SECONDS * 0.8:
        fail(f"the core's copy held for {HELD_SECONDS:g} s: {error!r} after {seconds:.2f} s")
    print(f"the core's new folder held open for {HELD_SECONDS:g} s: put in place and loaded after {seconds:.2f} s")

    # Another Blender's copy of the same build appears while this one copies: no wait, its copy loads.
    def copied_by_another(source, package_dir, staging):
        copy_build(source, package_dir, staging)
        copy_build(source, package_dir, os.path.join(os.path.dirname(staging), os.path.basename(staging).split(
            ".partial-")[0]))

    core_copy._copy_build = copied_by_another
    try:
        seconds, error = timed(core_copy.load, "raced_copy._core", str(package), str(out / "cores raced"))
    finally:
        core_copy._copy_build = copy_build
    left = sorted(os.listdir(out / "cores raced"))
    if error is not None or "raced_copy._core" not in sys.modules or seconds >= 2.0 or len(left) != 1:
        fail(f"a copy of the same build already in place: {error!r} after {seconds:.2f} s, left {left}")
    print(f"the same build's copy put in place by another process first: loaded after {seconds:.2f} s, no wait")

    # Held throughout: a clear error naming the folder (the add-on then loads the core in place).
    busy_files.WAIT_SECONDS = SHORT_WAIT_SECONDS
    core_copy._copy_build = copy_and_hold(None)
    try:
        seconds, error = timed(core_copy.load, "refused_copy._core", str(package), str(out / "cores refused"))
    finally:
        core_copy._copy_build = copy_build
        for release in holders:
            release()
    if not isinstance(error, OSError) or "could not be moved into place" not in str(error) or \
            str(out / "cores refused") not in str(error) or f"waited {SHORT_WAIT_SECONDS:g} s" not in str(error):
        fail(f"the core's copy held throughout: {error!r}")
    print(f"the core's new folder held open throughout: refused after {seconds:.2f} s ({error})")


def main():
    folder, frame, out = (pathlib.Path(argument) for argument in sys.argv[1:4])
    out.mkdir(parents=True, exist_ok=True)
    sys.path.insert(0, str(folder))
    import meniscus
    from meniscus import busy_files, core_copy

    if importlib.machinery.EXTENSION_SUFFIXES[0] != f".cp{sys.version_info.major}{sys.version_info.minor}-win_amd64.pyd":
        fail(f"not a Windows CPython: {importlib.machinery.EXTENSION_SUFFIXES}")
    check_core(meniscus, folder, frame, out)
    check_busy_files(busy_files, out)
    check_core_copy(core_copy, busy_files, folder, out)
    shutil.rmtree(out / "busy files", ignore_errors=True)
    print("legacy add-on check passed")


if __name__ == "__main__":
    main()
