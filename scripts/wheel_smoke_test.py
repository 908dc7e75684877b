"""Checks an installed meniscus wheel the way a user meets it: `import meniscus` from site-packages, a
reconstruction through the Python API, and the `meniscus` console script on a particle file.

    python scripts/wheel_smoke_test.py        (in an environment where the wheel is installed, not the source tree)

Used by scripts/package.sh for every wheel it builds and by the hosted wheel builds (cibuildwheel test-command).
Exits non-zero with the reason on any failure.
"""
import os
import pathlib
import shutil
import subprocess
import sys
import sysconfig
import tempfile

import numpy as np

# Run from anywhere but the source tree: python/meniscus must not shadow the installed package.
sys.path = [p for p in sys.path if pathlib.Path(p or ".").resolve() != pathlib.Path(__file__).resolve().parents[1]]

import meniscus  # noqa: E402


def fail(message):
    print(f"wheel smoke test FAILED: {message}", file=sys.stderr)
    sys.exit(1)


def main():
    package = pathlib.Path(meniscus.__file__).resolve().parent
    site = pathlib.Path(sysconfig.get_paths()["purelib"]).resolve()
    platsite = pathlib.Path(sysconfig.get_paths()["platlib"]).resolve()
    if site not in package.parents and platsite not in package.parents:
        fail(f"meniscus was imported from {package}, not from the environment's site-packages {site}")
    print(f"meniscus {meniscus.__version__} from {package}")

    # A jittered block of particles: one closed surface.
    rng = np.random.default_rng(7)
    grid = np.stack(np.meshgrid(*[np.arange(12)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    positions = (grid * 0.05 + rng.uniform(-0.005, 0.005, grid.shape)).astype(np.float32)
    mesh = meniscus.reconstruct(positions, particle_radius=0.025)
    check = meniscus.check_mesh(mesh)
    if len(mesh.triangles) < 1000 or not check["ok"]:
        fail(f"reconstruction gave {len(mesh.triangles)} triangles, check: {check['summary']}")
    print(f"API: {len(positions)} particles -> {len(mesh.triangles)} triangles, {check['summary']}")

    executable = shutil.which("meniscus", path=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""))
    if executable is None:
        fail("the console script 'meniscus' is not installed next to the interpreter")
    help_run = subprocess.run([executable, "--help"], capture_output=True, text=True)
    if help_run.returncode != 0 or "reconstruct" not in help_run.stdout:
        fail(f"'meniscus --help' exited {help_run.returncode}: {help_run.stdout}{help_run.stderr}")
    with tempfile.TemporaryDirectory() as folder:
        source = os.path.join(folder, "particles.npy")
        target = os.path.join(folder, "surface.ply")
        np.save(source, positions)
        run = subprocess.run([executable, "reconstruct", source, "-o", target, "-r", "0.025", "--check-mesh", "-q"],
                             capture_output=True, text=True)
        if run.returncode != 0 or not os.path.exists(target):
            fail(f"'meniscus reconstruct' exited {run.returncode}: {run.stderr}")
        written = meniscus.read_mesh(target)
        if len(written.triangles) != len(mesh.triangles):
            fail(f"the CLI wrote {len(written.triangles)} triangles, the API gave {len(mesh.triangles)}")
    print(f"CLI: {executable} ok")
    print("wheel smoke test passed")


if __name__ == "__main__":
    main()
