"""The Windows packages scripts/package.sh writes into dist/ (through scripts/package_windows.sh): their layout and
contents, checked here on Linux. Running them in Windows CPython and Windows Blender under Wine is
tests/windows/run.sh's job."""
import base64
import hashlib
import pathlib
import re
import subprocess
import tomllib
import zipfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DIST = ROOT / "dist"
VERSION = re.search(r"project\(meniscus VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text()).group(1)
TAGS = ("cp310", "cp311", "cp313")
# Runtime DLLs of mingw-w64 that no Windows has: the cores must have them linked in.
MINGW_RUNTIMES = re.compile(r"lib(stdc\+\+|gcc|winpthread|gomp)", re.I)


def windows_wheel(tag):
    path = DIST / f"meniscus-{VERSION}-{tag}-{tag}-win_amd64.whl"
    assert path.is_file(), f"no {path.name} in dist/ (run bash scripts/package.sh)"
    return path


@pytest.mark.parametrize("tag", TAGS)
def test_windows_wheel_is_complete_and_consistent(tag, tmp_path):
    with zipfile.ZipFile(windows_wheel(tag)) as wheel:
        names = set(wheel.namelist())
        assert f"meniscus/_core.{tag}-win_amd64.pyd" in names
        assert not any(name.endswith(".so") or name.startswith("meniscus.libs/") for name in names)
        assert {"meniscus/__init__.py", "meniscus/cli.py", f"meniscus-{VERSION}.dist-info/METADATA"} <= names
        assert f"Tag: {tag}-{tag}-win_amd64" in wheel.read(f"meniscus-{VERSION}.dist-info/WHEEL").decode()
        assert "meniscus = meniscus.cli:main" in wheel.read(f"meniscus-{VERSION}.dist-info/entry_points.txt").decode()
        # RECORD lists every file with its hash and size (pip checks them on install).
        record = wheel.read(f"meniscus-{VERSION}.dist-info/RECORD").decode().splitlines()
        listed = {line.split(",")[0]: line.split(",")[1:] for line in record}
        assert set(listed) == names
        for name, (digest, size) in listed.items():
            if name.endswith("RECORD"):
                continue
            data = wheel.read(name)
            expected = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
            assert digest == f"sha256={expected}" and int(size) == len(data), name
        core = tmp_path / "core.pyd"
        core.write_bytes(wheel.read(f"meniscus/_core.{tag}-win_amd64.pyd"))
    dump = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(core)], capture_output=True, text=True, check=True)
    imports = re.findall(r"DLL Name: (\S+)", dump.stdout)
    assert f"python{tag[2:]}.dll" in imports
    assert not [name for name in imports if MINGW_RUNTIMES.search(name)], imports


def test_windows_extension_zip_lists_the_windows_wheels():
    with zipfile.ZipFile(DIST / f"meniscus-{VERSION}-windows_x64.zip") as archive:
        manifest = tomllib.loads(archive.read("blender_manifest.toml").decode())
        assert manifest["platforms"] == ["windows-x64"]
        assert sorted(manifest["wheels"]) == [f"./wheels/{windows_wheel(tag).name}" for tag in ("cp311", "cp313")]
        for wheel in manifest["wheels"]:
            assert archive.read(wheel[2:]) == (DIST / wheel.split("/")[-1]).read_bytes()


def test_windows_legacy_zip_carries_the_cores_for_310_and_311():
    with zipfile.ZipFile(DIST / f"meniscus-{VERSION}-legacy-windows_x64.zip") as archive:
        names = set(archive.namelist())
    assert {f"meniscus/_core.{tag}-win_amd64.pyd" for tag in ("cp310", "cp311")} <= names
    assert "meniscus/__init__.py" in names and "meniscus/api.py" in names
    assert not any(name.endswith((".so", ".dll")) for name in names)


def test_no_wine_shim_in_the_windows_packages():
    """The harness's Wine shims (tests/windows/wine_shims.py: a ucrtbase.dll, Wine's own renamed, a sitecustomize.py)
    live in the test's Windows Pythons only, never in a package (nested wheels included)."""
    def names(archive):
        for name in archive.namelist():
            yield name
            if name.endswith(".whl"):
                with zipfile.ZipFile(archive.open(name)) as nested:
                    yield from names(nested)

    packages = sorted(DIST.glob(f"meniscus-{VERSION}-*win_amd64.whl")) + sorted(
        DIST.glob(f"meniscus-{VERSION}-*windows_x64.zip"))
    assert len(packages) == 5, [path.name for path in packages]
    for path in packages:
        with zipfile.ZipFile(path) as archive:
            shims = [name for name in names(archive)
                     if re.search(r"(^|/)(ucrtbase|ucrtwine)\.dll$|(^|/)sitecustomize\.py$", name, re.I)]
        assert not shims, f"{path.name} carries the test harness's Wine shims: {shims}"
