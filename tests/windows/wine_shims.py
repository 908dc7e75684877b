"""Test harness only: what a Windows CPython needs to run numpy and `bpy` under Debian 12's Wine 8.0 (the tests of
tests/windows/run.sh), put into that Python's folder, never into a package:

    python3 tests/windows/wine_shims.py build/windows/python-3.13
    WINEDLLOVERRIDES=ucrtbase=n,b wine64 build/windows/python-3.13/python.exe ...

- Wine 8.0's ucrtbase.dll leaves the C99 complex functions unimplemented, which numpy imports: 2.x calls them at
  import, 1.26 in its complex maths (np.exp of a complex array); the shim (tests/windows/ucrtbase_shim.c) implements
  them.
- Python 3.12+'s `platform` asks WMI for the Windows version through its _wmi module, which stops the process at
  Wine's unimplemented propsys.dll.VariantToString (bpy 5.2 calls `platform` at import); a sitecustomize.py in the
  Python's site-packages hides _wmi, and `platform` takes its fallback (the version from the system, as without WMI).
- Python 3.12+'s shutil.copy2 (so copytree, as the add-on's core copy uses it) calls KERNEL32's CopyFile2, which
  Wine 8.0 leaves unimplemented; the same sitecustomize.py hides _winapi.CopyFile2, and shutil copies as Python 3.11
  does (copyfile, then copystat).

The shim, a native ucrtbase.dll beside python.exe (which Wine loads first with the override above), exports the same
names as Wine's: the complex functions from the shim, every other name forwarded to ucrtwine.dll, a copy of Wine's own
ucrtbase.dll. Made again when the shim's source, this script or Wine's ucrtbase.dll changed.
"""
import pathlib
import re
import shutil
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
SOURCE = HERE / "ucrtbase_shim.c"
WINE_UCRTBASE = pathlib.Path("/usr/lib/x86_64-linux-gnu/wine/x86_64-windows/ucrtbase.dll")
FORWARD_TO = "ucrtwine"  # Wine's own ucrtbase, renamed so that it does not resolve to the shim


def exported_names(dll):
    dump = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(dll)], check=True, capture_output=True,
                          text=True).stdout
    table = dump.split("[Ordinal/Name Pointer] Table", 1)[1]
    return re.findall(r"^\s*\[\s*\d+\] (\S+)$", table.split("\n\n", 1)[0], re.MULTILINE)


SITECUSTOMIZE = """\
# Written by tests/windows/wine_shims.py (test harness, Wine only): Wine 8.0 cannot answer Python's WMI queries and
# has no CopyFile2.
import sys
import _winapi
sys.modules["_wmi"] = None
if hasattr(_winapi, "CopyFile2"):
    del _winapi.CopyFile2
"""


def main():
    folder = pathlib.Path(sys.argv[1])
    (folder / "Lib" / "site-packages" / "sitecustomize.py").write_text(SITECUSTOMIZE)
    shim, copy = folder / "ucrtbase.dll", folder / f"{FORWARD_TO}.dll"
    inputs = [SOURCE, pathlib.Path(__file__).resolve(), WINE_UCRTBASE]
    if shim.exists() and copy.exists() and shim.stat().st_mtime > max(path.stat().st_mtime for path in inputs):
        return
    # Compiled first: the names it implements are its shim_* symbols (most come from macros).
    # Linked to msvcrt.dll (mingw-w64's default C runtime), never to ucrtbase: the shim must not import itself.
    compiler = "x86_64-w64-mingw32-gcc-posix"  # what MENISCUS_WINDOWS_PACKAGES (scripts/lib.sh) installs
    objects = folder / "ucrtbase_shim.o"
    subprocess.run([compiler, "-O2", "-c", "-o", str(objects), str(SOURCE)], check=True)
    symbols = subprocess.run(["x86_64-w64-mingw32-nm", "-g", "--defined-only", str(objects)], check=True,
                             capture_output=True, text=True).stdout
    implemented = set(re.findall(r" T shim_(\w+)$", symbols, re.MULTILINE))
    names = exported_names(WINE_UCRTBASE)
    if not implemented <= set(names):
        raise SystemExit(f"Wine's ucrtbase.dll does not export {sorted(implemented - set(names))}")
    definitions = folder / "ucrtbase_shim.def"
    definitions.write_text("LIBRARY ucrtbase.dll\nEXPORTS\n" + "".join(
        f"  {name} = shim_{name}\n" if name in implemented else f"  {name} = {FORWARD_TO}.{name}\n"
        for name in names))
    shutil.copyfile(WINE_UCRTBASE, copy)
    subprocess.run([compiler, "-shared", "-static-libgcc", "-o", str(shim), str(objects), str(definitions)], check=True)
    definitions.unlink()
    objects.unlink()
    print(f"{shim}: {len(implemented)} complex functions, {len(names) - len(implemented)} forwarded to {copy.name}")


if __name__ == "__main__":
    main()
