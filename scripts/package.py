"""Assembles the Blender add-on packages of one platform from the wheels of the bpy-free `meniscus` package.

    python scripts/package.py --platform linux-x64 --out dist WHEEL...

Writes into --out:
- meniscus-<version>-<platform>.zip         the extension (Blender 4.2+): the add-on, blender_manifest.toml with
                                            `platforms` and `wheels` filled in, and the wheels under wheels/;
                                            Blender installs the wheel that matches its Python.
- meniscus-<version>-legacy-<platform>.zip  the legacy add-on (Blender 3.4-4.1, which cannot install wheels): one
                                            folder `meniscus` with the add-on, the library's modules and the
                                            compiled core of every given wheel (one per Python version), plus the
                                            shared libraries the wheels vendor, next to the core.
<platform> in file names uses '_' (linux_x64), as Blender's own `extension build --split-platforms` does.
Called by scripts/package.sh (Linux) and scripts/package_windows.sh (Windows, mingw-w64), here, and by the hosted
workflow (.github/workflows/wheels.yml) for macOS and its MSVC build for Windows.
"""
import argparse
import pathlib
import re
import subprocess
import sys
import tempfile
import zipfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
ADDON = ROOT / "addon" / "meniscus"
LIBRARY = ROOT / "python" / "meniscus"
PLATFORMS = ("linux-x64", "windows-x64", "windows-arm64", "macos-x64", "macos-arm64")
# Wheel platform tags per extension platform (the checks Blender itself makes when it picks a wheel).
WHEEL_TAG_PATTERNS = {
    "linux-x64": r"(manylinux\w*|linux)_x86_64$",
    "windows-x64": r"win_amd64$",
    "windows-arm64": r"win_arm64$",
    "macos-x64": r"macosx_\w+_(x86_64|universal2)$",
    "macos-arm64": r"macosx_\w+_(arm64|universal2)$",
}
SKIPPED = ("__pycache__", ".pyc", ".partial")


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text()
    return re.search(r"project\(meniscus VERSION ([0-9.]+)", text).group(1)


def source_files(folder):
    """(path, path relative to folder) of the files to package, sorted, without caches."""
    for path in sorted(folder.rglob("*")):
        if path.is_file() and not any(part in str(path) for part in SKIPPED):
            yield path, path.relative_to(folder)


def wheel_tags(wheel):
    name, version, *rest = wheel.name[:-len(".whl")].split("-")
    python_tag, abi_tag, platform_tag = rest[-3:]
    return python_tag, abi_tag, platform_tag


def write_manifest(archive, platform, wheels):
    text = (ADDON / "blender_manifest.toml").read_text()
    listed = ", ".join(f'"./wheels/{wheel.name}"' for wheel in wheels)
    text = re.sub(r"^platforms = \[.*\]$", f'platforms = ["{platform}"]', text, flags=re.M)
    text = re.sub(r"^wheels = \[.*\]$", f"wheels = [{listed}]", text, flags=re.M)
    archive.writestr("blender_manifest.toml", text)


def extension_zip(path, platform, wheels):
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for source, relative in source_files(ADDON):
            if relative.name != "blender_manifest.toml":
                archive.write(source, relative.as_posix())
        write_manifest(archive, platform, wheels)
        for wheel in wheels:
            archive.write(wheel, f"wheels/{wheel.name}")  # unmodified, as the extension platform requires
        archive.write(ROOT / "LICENSE", "LICENSE")


def vendored_core(wheel, folder):
    """Extracts a wheel's compiled core and the shared libraries it vendors into folder, arranged so that the core
    finds them from the legacy layout (everything inside the one add-on folder)."""
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        cores = [n for n in names if re.match(r"meniscus/_core\.[^/]+\.(so|pyd)$", n)]
        if len(cores) != 1:
            raise SystemExit(f"{wheel.name}: expected one compiled core, found {cores}")
        core = folder / pathlib.PurePosixPath(cores[0]).name
        core.write_bytes(archive.read(cores[0]))
        # auditwheel (Linux) and delvewheel (MSVC Windows build) put libraries in meniscus.libs/ beside the package (the
        # mingw-w64 Windows cores have none: their runtimes are linked in); delocate
        # (macOS) in meniscus/.dylibs/, found through @loader_path, which the legacy layout keeps as it is.
        for name in names:
            if name.endswith("/"):
                continue
            if name.startswith("meniscus.libs/"):
                (folder / pathlib.PurePosixPath(name).name).write_bytes(archive.read(name))
            elif name.startswith("meniscus/.dylibs/"):
                target = folder / ".dylibs" / pathlib.PurePosixPath(name).name
                target.parent.mkdir(exist_ok=True)
                target.write_bytes(archive.read(name))
    if core.suffix == ".so" and sys.platform.startswith("linux"):
        # auditwheel's run path points at ../meniscus.libs; in the add-on the libraries sit beside the core.
        subprocess.run(["patchelf", "--set-rpath", "$ORIGIN", str(core)], check=True)
    return core


def legacy_zip(path, wheels):
    with tempfile.TemporaryDirectory() as temporary:
        folder = pathlib.Path(temporary)
        for wheel in wheels:
            vendored_core(wheel, folder)
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
            for source, relative in source_files(ADDON):
                if relative.name != "blender_manifest.toml":  # 4.2+ would take the zip for an extension
                    archive.write(source, f"meniscus/{relative.as_posix()}")
            for source, relative in source_files(LIBRARY):
                if relative.name != "__init__.py":  # the add-on's __init__ imports the library beside it
                    archive.write(source, f"meniscus/{relative.as_posix()}")
            for source, relative in source_files(folder):
                archive.write(source, f"meniscus/{relative.as_posix()}")
            archive.write(ROOT / "LICENSE", "meniscus/LICENSE")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--platform", required=True, choices=PLATFORMS)
    parser.add_argument("--out", default=str(ROOT / "dist"))
    parser.add_argument("--extension-pythons", default="cp311,cp313",
                        help="Python tags whose wheels go into the extension (the Pythons Blender 4.2+ embed)")
    parser.add_argument("--legacy-pythons", default="cp310,cp311",
                        help="Python tags whose cores go into the legacy add-on (Blender 3.4-4.0: 3.10, 4.1: 3.11; "
                             "Linux distributions' Blender builds use their system Python, Debian 12's 3.11)")
    parser.add_argument("wheels", nargs="+", type=pathlib.Path)
    args = parser.parse_args()

    version = project_version()
    pattern = re.compile(WHEEL_TAG_PATTERNS[args.platform])
    wheels = sorted(set(args.wheels))
    for wheel in wheels:
        if not wheel.name.startswith(f"meniscus-{version}-"):
            raise SystemExit(f"{wheel.name}: not a meniscus {version} wheel")
        if not pattern.search(wheel_tags(wheel)[2]):
            raise SystemExit(f"{wheel.name}: not a wheel for {args.platform}")
    extension_pythons = set(args.extension_pythons.split(","))
    extension_wheels = [w for w in wheels if wheel_tags(w)[0] in extension_pythons]
    missing = extension_pythons - {wheel_tags(w)[0] for w in extension_wheels}
    if missing:
        raise SystemExit(f"no wheel for {', '.join(sorted(missing))}: the extension would not load in every Blender")

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    suffix = args.platform.replace("-", "_")
    extension = out / f"meniscus-{version}-{suffix}.zip"
    legacy = out / f"meniscus-{version}-legacy-{suffix}.zip"
    extension_zip(extension, args.platform, extension_wheels)
    legacy_pythons = set(args.legacy_pythons.split(","))
    legacy_zip(legacy, [w for w in wheels if wheel_tags(w)[0] in legacy_pythons])
    print(extension)
    print(legacy)


if __name__ == "__main__":
    main()
