"""Installs a meniscus win_amd64 wheel into a Windows CPython under Wine with that Python's own pip, runs
tests/windows/check_wheel.py there, and compares what it wrote with the Linux build:

    python3 tests/windows/test_wheels.py --python build/windows/python-3.11 --wheel dist/meniscus-V-cp311-...whl \
        --numpy NUMPY_WHEEL --linux-cli build/bin/meniscus [--quick]     (tests/windows/run.sh, in scripts/test.sh)

--quick: only the install, `import meniscus` and the shared frame through the Python API (check_wheel.py --quick).
--legacy-zip ZIP: also the legacy Blender zip unpacked and used as a library in that Python (check_legacy_addon.py):
its core for this Python makes the Linux mesh; the add-on's replacement of files held open by another program.
The meshes (Python API, console script, non-ASCII paths, the long path where Windows wrote it) must have the Linux
mesh's triangles and its vertices within float tolerance; the readers must give the same particles. Needs WINEPREFIX.
Exits non-zero with the reason on any failure.
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import zipfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data"
WINE = "/usr/lib/wine/wine64"  # Debian's wine64 does not put its loader on PATH
sys.path[:0] = [str(ROOT / "tests" / "portability"), str(ROOT / "tests" / "windows"), str(ROOT / "build" / "python")]
from check_cli import compare  # noqa: E402  (the Linux-vs-other-build mesh comparison)
import check_wheel  # noqa: E402  (its reader summary, here with the Linux build's meniscus)


def windows_path(path):
    """Wine maps the Unix root to drive Z:."""
    return "Z:" + str(pathlib.Path(path).resolve()).replace("/", "\\")


def wine(python, *arguments):
    # Python under Wine stops at start-up when its standard streams are files (init_sys_streams: invalid handle):
    # every stream is a pipe here. Wine decodes the command line in the locale's encoding: UTF-8.
    # WinPython's pip writes console scripts that find python.exe on PATH ("#!python.exe"), as its own shells set.
    environment = dict(os.environ, LC_ALL="C.UTF-8", LANG="C.UTF-8", WINEDEBUG="-all", PYTHONUTF8="1",
                       WINEPATH=windows_path(python))
    command = [WINE, str(pathlib.Path(python) / "python.exe"), *arguments]
    completed = subprocess.run(command, input="", capture_output=True, text=True, encoding="utf-8", errors="replace",
                               env=environment)
    if completed.returncode != 0:
        raise SystemExit(f"{' '.join(command)} exited {completed.returncode}:\n{completed.stdout}{completed.stderr}")
    return completed.stdout


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--python", required=True, help="folder of the Windows CPython (python.exe)")
    parser.add_argument("--wheel", required=True)
    parser.add_argument("--numpy", required=True, help="the numpy win_amd64 wheel for that Python")
    parser.add_argument("--linux-cli", required=True)
    parser.add_argument("--quick", action="store_true", help="install, import and one frame through the API only")
    parser.add_argument("--legacy-zip", help="the legacy Windows Blender zip, checked in this Python too")
    args = parser.parse_args()
    if "WINEPREFIX" not in os.environ:
        raise SystemExit("set WINEPREFIX (a Wine prefix under build/)")

    # As a user installs it: that Python's pip, which writes Scripts\meniscus.exe for the console script.
    wine(args.python, "-m", "pip", "install", "-q", "--no-deps", "--no-index", "--force-reinstall",
         "--no-warn-script-location", "--disable-pip-version-check", windows_path(args.wheel), windows_path(args.numpy))

    try:
        check(args)
    finally:  # leave the Python as it was: the Blender suite's add-on must not find a meniscus there
        wine(args.python, "-m", "pip", "uninstall", "-q", "-y", "meniscus")
    print(f"{pathlib.Path(args.wheel).name}: passed under Wine")


def check(args):
    with tempfile.TemporaryDirectory(prefix="meniscus_windows_wheel_") as folder:
        folder = pathlib.Path(folder)
        out = folder / "out"
        print(wine(args.python, windows_path(ROOT / "tests" / "windows" / "check_wheel.py"), windows_path(SHARED),
                   windows_path(out), *(["--quick"] if args.quick else [])), end="")

        linux_ply = folder / "linux.ply"
        frame = SHARED / "splashsurf" / check_wheel.FRAME_NAME
        subprocess.run([args.linux_cli, "reconstruct", str(frame), "-o", str(linux_ply), *check_wheel.ARGUMENTS],
                       check=True)
        meshes = ["api.ply"] if args.quick else ["api.ply", "cli.ply", "unicode-api.ply", "unicode-0001.ply",
                                                 "unicode-0002.ply"]
        if (out / "long-path.ply").exists():
            meshes.append("long-path.ply")
        for name in meshes:
            compare(linux_ply, out / name, f"Windows {name}")
        if args.legacy_zip:
            check_legacy_zip(args, folder, linux_ply)
        if args.quick:
            return

        windows_readers = json.loads((out / "readers.json").read_text(encoding="utf-8"))
        for name, windows in windows_readers.items():
            path = next((SHARED / kind / name for kind in ("splashsurf", "sequence") if (SHARED / kind / name).exists()))
            linux = check_wheel.reader_summary(path)
            same_sums = all(abs(a - b) <= 1e-9 * max(1.0, abs(b)) for a, b in zip(windows["position_sum"],
                                                                                  linux["position_sum"]))
            if windows["count"] != linux["count"] or windows["attributes"] != linux["attributes"] or not same_sums:
                raise SystemExit(f"reader on {name}: Windows {windows}, Linux {linux}")
        print(f"readers: the same particles as Linux in {len(windows_readers)} files")


def check_legacy_zip(args, folder, linux_ply):
    unpacked, out = folder / "legacy add-on", folder / "legacy out"
    with zipfile.ZipFile(args.legacy_zip) as archive:
        archive.extractall(unpacked)
    print(wine(args.python, windows_path(ROOT / "tests" / "windows" / "check_legacy_addon.py"), windows_path(unpacked),
               windows_path(SHARED / "splashsurf" / check_wheel.FRAME_NAME), windows_path(out)), end="")
    compare(linux_ply, out / "legacy.ply", f"Windows {pathlib.Path(args.legacy_zip).name}")


if __name__ == "__main__":
    main()
