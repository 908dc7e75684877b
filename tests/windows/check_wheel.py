"""Runs inside a Windows CPython (under Wine here) where a meniscus win_amd64 wheel was installed with pip, the way a
Windows user meets it; tests/windows/test_wheels.py starts it and compares what it writes with the Linux build:

    python.exe check_wheel.py SHARED_DATA_DIR OUTPUT_DIR [--quick]

Writes into OUTPUT_DIR: api.ply (the shared frame through the Python API; with --quick only that, after the import
and install checks), cli.ply (through the `meniscus` console script, Scripts\\meniscus.exe), readers.json (what the
readers give for every shared sample file) and results.json (what happened to the long path). Exits non-zero with the
reason on any failure.
"""
import json
import os
import pathlib
import shutil
import subprocess
import sys
import sysconfig
import threading

import meniscus

FRAME_NAME = "double_dam_break_frame_26_4732_particles.vtk"
# The command line's defaults, spelled out: the same parameters as reconstruct()'s defaults (one schema).
ARGUMENTS = ["-r", "0.025", "-l", "2", "-c", "0.5", "-t", "0.6", "-q"]
# Windows codes of a process killed by a fault (access violation, stack overflow, abort...) are 0xC0000000 and up.
CRASH_CODES = range(0xC0000000, 0x100000000)


def fail(message):
    print(f"Windows wheel check FAILED: {message}", file=sys.stderr)
    sys.exit(1)


def run(arguments, expect_success=True):
    completed = subprocess.run([str(a) for a in arguments], capture_output=True, text=True, encoding="utf-8",
                               errors="replace", stdin=subprocess.DEVNULL)
    code = completed.returncode & 0xFFFFFFFF
    if code in CRASH_CODES:
        fail(f"{arguments} crashed with 0x{code:08X}: {completed.stderr}")
    if expect_success and completed.returncode != 0:
        fail(f"{arguments} exited {completed.returncode}: {completed.stdout}{completed.stderr}")
    return completed


def reader_summary(path):
    particles = meniscus.read_particles(path)
    positions = particles.positions
    return {"count": int(len(positions)), "attributes": sorted(particles.attributes),
            "position_sum": [float(v) for v in positions.astype("float64").sum(axis=0)]}


def check_complex_maths():
    """numpy's complex functions come from the C runtime's (under Wine 8 on Python 3.13: the harness's ucrtbase shim,
    tests/windows/wine_shims.py, whose calling convention must match MSVC's for doubles and floats)."""
    import numpy as np
    for dtype in (np.complex128, np.complex64):
        z = np.array([3 + 4j, -4 + 0j, 1j * np.pi], dtype=dtype)
        results = {"abs": (np.abs(z[0]), 5), "sqrt": (np.sqrt(z[1]), 2j), "exp": (np.exp(z[2]), -1),
                   "power": (z[0] ** 2, -7 + 24j), "log": (np.log(z[1]), np.log(4) + 1j * np.pi),
                   "cos": (np.cos(z[0]), complex(np.cos(3) * np.cosh(4), -np.sin(3) * np.sinh(4)))}
        for name, (value, expected) in results.items():
            if abs(complex(value) - expected) > 1e-4 * max(1.0, abs(expected)):
                fail(f"numpy's complex {name} ({np.dtype(dtype).name}) gives {value}, not {expected}")
    print(f"numpy {np.__version__}: complex maths ok")


def main():
    shared, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    quick = sys.argv[3:] == ["--quick"]
    out.mkdir(parents=True, exist_ok=True)
    frame = shared / "splashsurf" / FRAME_NAME
    results = {}

    # Installed by pip into this Python's site-packages, with the console script beside the interpreter.
    package = pathlib.Path(meniscus.__file__).resolve().parent
    site = pathlib.Path(sysconfig.get_paths()["platlib"]).resolve()
    if site not in package.parents:
        fail(f"meniscus was imported from {package}, not from {site}")
    cli = pathlib.Path(sysconfig.get_paths()["scripts"]) / "meniscus.exe"
    if not cli.is_file():
        fail(f"pip did not install the console script {cli}")
    print(f"meniscus {meniscus.__version__} from {package}; CLI {cli}")
    check_complex_maths()

    # The shared frame through the API and through the console script.
    particles = meniscus.read_particles(frame)
    mesh = meniscus.reconstruct(particles.positions, 0.025)
    meniscus.write_mesh(mesh, out / "api.ply")
    if quick:
        print(f"API: {len(mesh.triangles)} triangles (quick check)")
        return
    run([cli, "reconstruct", frame, "-o", out / "cli.ply", *ARGUMENTS])
    print(f"API and CLI: {len(mesh.triangles)} triangles")

    # The readers on every shared sample file (legacy VTK, BGEO) and two frames of the sequence.
    samples = sorted((shared / "splashsurf").glob("*.vtk")) + sorted((shared / "splashsurf").glob("*.bgeo"))
    samples += sorted((shared / "sequence").glob("*.vtk"))[:2]
    summaries = {path.name: reader_summary(path) for path in samples}
    (out / "readers.json").write_text(json.dumps(summaries, indent=1), encoding="utf-8")
    print(f"readers: {len(summaries)} files")

    # Exit codes, and errors that name what is wrong.
    if run([cli, "--help"]).stdout.count("reconstruct") == 0:
        fail("'meniscus --help' does not list reconstruct")
    missing = out / "no such file.vtk"
    refused = run([cli, "reconstruct", missing, "-o", out / "x.ply", "-r", "0.025"], expect_success=False)
    if refused.returncode == 0 or "no such file.vtk" not in refused.stderr:
        fail(f"a missing input: exit {refused.returncode}, stderr {refused.stderr!r}")
    refused = run([cli, "reconstruct", frame, "-o", out / "x.ply", "-r", "-1"], expect_success=False)
    if refused.returncode == 0 or "-r" not in refused.stderr and "radius" not in refused.stderr:
        fail(f"a negative radius: exit {refused.returncode}, stderr {refused.stderr!r}")
    garbage = out / "garbage.vtk"
    garbage.write_bytes(b"# vtk DataFile Version 4.1\nnot really\n")
    refused = run([cli, "reconstruct", garbage, "-o", out / "x.ply", "-r", "0.025"], expect_success=False)
    if refused.returncode == 0 or "garbage.vtk" not in refused.stderr:
        fail(f"a malformed file: exit {refused.returncode}, stderr {refused.stderr!r}")
    try:
        meniscus.read_particles(garbage)
        fail("read_particles accepted a malformed file")
    except meniscus.FormatError as error:
        if "garbage.vtk" not in str(error):
            fail(f"FormatError does not name the file: {error}")
    print("exit codes and error messages: ok")

    # Non-ASCII characters and spaces in folder and file names: the API and a sequence through the console script.
    folder = out / "été 粒子 données"
    folder.mkdir(exist_ok=True)
    for number in (1, 2):
        shutil.copy(frame, folder / f"flüssigkeit {number:04d}.vtk")
    unicode_particles = meniscus.read_particles(folder / "flüssigkeit 0001.vtk")
    meniscus.write_mesh(meniscus.reconstruct(unicode_particles.positions, 0.025), folder / "oberfläche api.ply")
    run([cli, "reconstruct", folder / "flüssigkeit {}.vtk", "-o", folder / "oberfläche {}.ply", *ARGUMENTS])
    for name in ("oberfläche api.ply", "oberfläche 0001.ply", "oberfläche 0002.ply"):
        if not (folder / name).is_file():
            fail(f"nothing written at {folder / name}")
        shutil.copy(folder / name, out / f"unicode-{name.split()[-1]}")
    print("non-ASCII and spaces: ok")

    # Text outputs are written with '\n' line ends on Windows too (files move between farm machines and platforms).
    run([cli, "reconstruct", frame, "-o", out / "text.obj", "--stats", out / "stats.json", *ARGUMENTS])
    run([cli, "farm", "openjd", folder / "flüssigkeit {}.vtk", "-o", out / "farm_{}.ply", "-s", "1", "-e", "2",
         "-r", "0.025", "--bundle", out / "bundle"])
    texts = [out / "text.obj", out / "stats.json", *sorted((out / "bundle").iterdir())]
    for path in texts:
        if b"\r\n" in path.read_bytes():
            fail(f"{path} has CRLF line ends")
    print(f"text outputs without CRLF: {len(texts)} files")

    # Replacing a mesh that another program has open for reading, as a player or viewer does while a farm re-renders
    # a frame: Windows refuses the rename until that program lets go (Python's open, like most programs' readers,
    # does not share delete access), so the writer waits for it a while, then says which file it could not replace.
    replaced = out / "replaced.ply"
    run([cli, "reconstruct", frame, "-o", replaced, *ARGUMENTS])
    other_frame = shared / "splashsurf" / "double_dam_break_frame_01_4732_particles.vtk"
    with open(replaced, "rb") as reader:
        threading.Timer(1.0, reader.close).start()
        run([cli, "reconstruct", other_frame, "-o", replaced, *ARGUMENTS])
    expected = meniscus.reconstruct(meniscus.read_particles(other_frame).positions, 0.025)
    if len(meniscus.read_mesh(replaced).triangles) != len(expected.triangles):
        fail("the mesh that was open for reading was not replaced by the new one")
    with open(replaced, "rb"):
        refused = run([cli, "reconstruct", frame, "-o", replaced, *ARGUMENTS], expect_success=False)
    if refused.returncode == 0 or "replaced.ply" not in refused.stderr:
        fail(f"replacing a file held open: exit {refused.returncode}, stderr {refused.stderr!r}")
    if len(meniscus.read_mesh(replaced).triangles) != len(expected.triangles):
        fail("a refused replacement changed the file")
    print(f"replacing a mesh open in another program: waited for it; refused after a while ({refused.stderr.strip()})")

    # A path longer than Windows' classic limit (260 characters): written, or refused with a message naming it.
    long_folder = out.joinpath(*["a-rather-long-folder-name-for-a-shot" for _ in range(8)])
    long_output = long_folder / "surface_0001.ply"
    assert len(str(long_output)) > 260
    try:
        long_folder.mkdir(parents=True, exist_ok=True)
        made = True
    except OSError as error:
        made = False
        results["long_path_folder"] = f"refused by Windows: {error}"
    if made:
        completed = run([cli, "reconstruct", frame, "-o", long_output, *ARGUMENTS], expect_success=False)
        if completed.returncode == 0:
            if not long_output.is_file():
                fail(f"exit 0 but nothing at the long path {long_output}")
            shutil.copy(long_output, out / "long-path.ply")
            results["long_path"] = "written"
        elif "surface_0001.ply" in completed.stderr:
            results["long_path"] = f"refused: {completed.stderr.strip()}"
        else:
            fail(f"a long output path: exit {completed.returncode} without naming the file: {completed.stderr!r}")
    print(f"path of {len(str(long_output))} characters: {results.get('long_path', results.get('long_path_folder'))}")
    (out / "results.json").write_text(json.dumps(results, indent=1), encoding="utf-8")
    print("Windows wheel check passed")


if __name__ == "__main__":
    main()
