"""What the farm tests share: the runners' venv (scripts/farm_venv.sh), a small sequence, a local reference run,
and processes that are always ended by their id."""
import os
import pathlib
import shutil
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("MENISCUS_BUILD", ROOT / "build"))
SEQUENCE = ROOT.parent / "shared" / "data" / "sequence"
FRAMES = range(1, 7)
# Small and quick: 12 096 particles a frame at cubes of one radius.
PIPELINE = ["-r", "0.025", "-c", "1.0", "--threads", "1"]


def farm_python() -> pathlib.Path:
    """The venv with openjd and dask (made once by scripts/farm_venv.sh; later calls cost a stamp check)."""
    result = subprocess.run(["bash", str(ROOT / "scripts" / "farm_venv.sh")], cwd=ROOT, capture_output=True, text=True,
                            timeout=600)
    assert result.returncode == 0, result.stderr
    return ROOT / result.stdout.strip().splitlines()[-1]


def use_farm_packages() -> pathlib.Path:
    """Makes the farm venv's packages (dask, distributed) importable in this test process, ahead of the system's:
    the venv is built on this same Python with its system packages, so the two agree. Returns the venv's Python."""
    python = farm_python()
    site_packages = python.parent.parent / "lib" / f"python{sys.version_info[0]}.{sys.version_info[1]}" / "site-packages"
    assert site_packages.is_dir(), f"{site_packages}: the farm venv is for another Python than {sys.executable}"
    sys.path.insert(0, str(site_packages))
    return python


def environment() -> dict:
    """The environment of processes that import meniscus: the staged package of this build first."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(BUILD / "python"), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def make_sequence(folder: pathlib.Path, corrupt=()) -> pathlib.Path:
    """Frames 1-6 as fluid_0001.vtk ...; frames in corrupt are cut short (unreadable). Returns the input pattern."""
    folder.mkdir(parents=True, exist_ok=True)
    for n in FRAMES:
        source = SEQUENCE / f"double_dam_break_{n:04d}.vtk"
        if n in corrupt:
            (folder / f"fluid_{n:04d}.vtk").write_bytes(source.read_bytes()[:3000])
        else:
            shutil.copy(source, folder / f"fluid_{n:04d}.vtk")
    return folder / "fluid_{}.vtk"


def local_run(cli: str, folder: pathlib.Path) -> pathlib.Path:
    """One local `meniscus reconstruct` of frames 1-6 into folder: the reference the farm runs must equal."""
    inputs = make_sequence(folder / "in")
    result = subprocess.run([cli, "reconstruct", str(inputs), "-o", str(folder / "out" / "surface_{}.ply"), "-s", "1",
                             "-e", "6", *PIPELINE, "-q"], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return folder / "out"


def meshes(folder: pathlib.Path) -> dict:
    return {path.name: path.read_bytes() for path in sorted(folder.glob("surface_*.ply"))}


def python_command(python=None):
    return [str(python or sys.executable), "-m", "meniscus"]


def end_process(process: subprocess.Popen) -> None:
    """Ends a process this test started, by its id: politely, then by force."""
    if process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(timeout=10)
