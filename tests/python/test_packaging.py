"""What users install, as built by scripts/package.sh into dist/: the wheels (installed into clean environments and
used as a user would), the Blender extension zip and the legacy add-on zip (their layout and manifest; installing
them into Blender is tests/blender/run.sh's job). scripts/test.sh builds dist/ before running these."""
import ast
import glob
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import zipfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DIST = ROOT / "dist"
VERSION = re.search(r"project\(meniscus VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text()).group(1)
EXTENSION = DIST / f"meniscus-{VERSION}-linux_x64.zip"
LEGACY = DIST / f"meniscus-{VERSION}-legacy-linux_x64.zip"


def python_for(version):
    """A CPython interpreter of that version (pyenv's, as scripts/lib.sh finds them)."""
    root = os.environ.get("PYENV_ROOT", os.path.expanduser("~/.pyenv"))
    found = sorted(glob.glob(f"{root}/versions/{version}.*/bin/python{version}"))
    assert found, f"no Python {version} (scripts/package.sh needs it too)"
    return found[-1]


def wheel_for(tag):
    found = sorted(DIST.glob(f"meniscus-{VERSION}-{tag}-{tag}-manylinux_*_x86_64.whl"))
    assert len(found) == 1, f"expected one {tag} wheel in dist/, found {found} (run bash scripts/package.sh)"
    return found[0]


def test_one_version_everywhere():
    manifest = (ROOT / "addon" / "meniscus" / "blender_manifest.toml").read_text()
    assert re.search(rf'^version = "{re.escape(VERSION)}"$', manifest, re.M), "manifest version differs from CMake's"
    init = ast.parse((ROOT / "addon" / "meniscus" / "__init__.py").read_text())
    bl_info = next(ast.literal_eval(node.value) for node in init.body
                   if isinstance(node, ast.Assign) and node.targets[0].id == "bl_info")
    assert ".".join(map(str, bl_info["version"])) == VERSION, "bl_info version differs from CMake's"


@pytest.mark.parametrize("version, tag", [("3.10", "cp310"), ("3.11", "cp311"), ("3.13", "cp313")])
def test_wheel_installs_into_a_clean_environment_and_runs(version, tag):
    wheel = wheel_for(tag)
    with tempfile.TemporaryDirectory(prefix=f"meniscus_wheel_{tag}_") as folder:
        venv = pathlib.Path(folder) / "venv"
        subprocess.run([python_for(version), "-m", "venv", str(venv)], check=True)
        python = str(venv / "bin" / "python")
        install = subprocess.run([python, "-m", "pip", "install", "-q", "--disable-pip-version-check", str(wheel)],
                                 capture_output=True, text=True)
        assert install.returncode == 0, install.stdout + install.stderr
        # Run from a folder outside the source tree, so that nothing but the installed package can be imported.
        smoke = subprocess.run([python, str(ROOT / "scripts" / "wheel_smoke_test.py")], capture_output=True, text=True,
                               cwd=folder)
        assert smoke.returncode == 0, smoke.stdout + smoke.stderr
        assert "wheel smoke test passed" in smoke.stdout
        assert str(venv) in smoke.stdout  # imported from the venv's site-packages


def test_wheel_holds_the_library_and_no_blender_code():
    with zipfile.ZipFile(wheel_for("cp311")) as wheel:
        names = wheel.namelist()
        entry_points = wheel.read(f"meniscus-{VERSION}.dist-info/entry_points.txt").decode()
        metadata = wheel.read(f"meniscus-{VERSION}.dist-info/METADATA").decode()
    assert "meniscus/api.py" in names and "meniscus/cli.py" in names
    assert any(re.fullmatch(r"meniscus/_core\.cpython-311-x86_64-linux-gnu\.so", n) for n in names)
    assert any(n.startswith("meniscus.libs/libgomp") for n in names), "auditwheel should vendor libgomp"
    assert not any("blender" in n or n.endswith(".toml") for n in names), "the wheel must stay bpy-free"
    assert re.search(r"^meniscus = meniscus\.cli:main$", entry_points, re.M)
    assert "GPL-3.0-or-later" in metadata


def test_extension_zip_lists_one_wheel_per_blender_python():
    with zipfile.ZipFile(EXTENSION) as archive:
        names = set(archive.namelist())
        manifest = archive.read("blender_manifest.toml").decode()
    wheels = re.search(r"^wheels = \[(.*)\]$", manifest, re.M).group(1)
    listed = re.findall(r'"\./(wheels/[^"]+)"', wheels)
    assert sorted(re.search(r"-(cp3\d+)-", w).group(1) for w in listed) == ["cp311", "cp313"]
    assert all(w in names for w in listed), (listed, names)
    assert re.search(r'^platforms = \["linux-x64"\]$', manifest, re.M)
    assert 'license = ["SPDX:GPL-3.0-or-later"]' in manifest
    assert re.search(r"^\[permissions\]\nfiles = ", manifest, re.M), "file access must be declared"
    assert "network" not in manifest  # nothing is downloaded at run time
    assert "__init__.py" in names and "blender/app_handlers.py" in names and "LICENSE" in names
    assert not any(n.endswith((".so", ".pyd", ".dylib")) for n in names), "compiled code only inside the wheels"
    # The add-on finds the library as the installed wheel (top-level `meniscus`), never by a path of its own.
    init = (ROOT / "addon" / "meniscus" / "__init__.py").read_text()
    assert "from meniscus import api, cache, parameters, sequence" in init and "sys.path" not in init


def test_legacy_zip_is_one_add_on_folder_with_a_core_per_python():
    with zipfile.ZipFile(LEGACY) as archive:
        names = archive.namelist()
        init = archive.read("meniscus/__init__.py").decode()
    assert {n.split("/")[0] for n in names} == {"meniscus"}
    assert "bl_info" in init and "meniscus/blender_manifest.toml" not in names  # 4.2+ would take it for an extension
    cores = sorted(n for n in names if re.fullmatch(r"meniscus/_core\.cpython-3\d+-x86_64-linux-gnu\.so", n))
    assert cores == ["meniscus/_core.cpython-310-x86_64-linux-gnu.so", "meniscus/_core.cpython-311-x86_64-linux-gnu.so"]
    assert any(re.fullmatch(r"meniscus/libgomp-[0-9a-f]+\.so\.1\.0\.0", n) for n in names)
    assert {"meniscus/api.py", "meniscus/parameters.py", "meniscus/blender/app_handlers.py"} <= set(names)


@pytest.mark.parametrize("version", ["3.10", "3.11"])
def test_legacy_zip_core_loads_its_bundled_libraries(version):
    # Unpacked as Blender's add-on installer does; the core must find the vendored libgomp beside itself.
    with tempfile.TemporaryDirectory(prefix="meniscus_legacy_") as folder:
        with zipfile.ZipFile(LEGACY) as archive:
            archive.extractall(folder)
        rpath = subprocess.run(["readelf", "-d", glob.glob(f"{folder}/meniscus/_core.cpython-{version.replace('.', '')}*")[0]],
                               capture_output=True, text=True).stdout
        assert "[$ORIGIN]" in rpath, rpath
        code = ("import sys; sys.path.insert(0, sys.argv[1]); import meniscus; "
                "from meniscus import api; print(api._core.__file__); print(meniscus.reconstruct.__module__)")
        # The add-on's __init__ needs no bpy until register(); numpy comes from a clean environment.
        venv = pathlib.Path(folder) / "venv"
        subprocess.run([python_for(version), "-m", "venv", str(venv)], check=True)
        python = str(venv / "bin" / "python")
        subprocess.run([python, "-m", "pip", "install", "-q", "--disable-pip-version-check", "numpy"], check=True)
        run = subprocess.run([python, "-c", code, folder], capture_output=True, text=True, cwd=folder,
                             env={k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"})
        assert run.returncode == 0, run.stdout + run.stderr
        assert run.stdout.splitlines()[0].startswith(f"{folder}/meniscus/_core.cpython-{version.replace('.', '')}")
