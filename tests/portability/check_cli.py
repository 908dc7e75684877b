"""Another build's command line against the Linux GCC build's, on a shared frame: the same triangles and vertices
within float tolerance, also for a sequence read from and written to paths with non-ASCII characters.

    python3 tests/portability/check_cli.py --wine /usr/lib/wine/wine64 --windows-cli build-windows/bin/meniscus.exe \
        --linux-cli build/bin/meniscus                      (scripts/build_windows.sh: mingw-w64 under Wine)
    python3 tests/portability/check_cli.py --windows-cli build-clang-asan/bin/meniscus --linux-cli build/bin/meniscus \
        --label clang                                       (scripts/test_sanitizers.sh: clang, libc++, libomp)

Exits non-zero with the reason on any difference.
"""
import argparse
import os
import pathlib
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[2]
FRAME = ROOT.parent / "shared" / "data" / "splashsurf" / "double_dam_break_frame_26_4732_particles.vtk"
# The full pipeline (decimation, weights, smoothing, volume restoration, normals) with the velocity-free frame.
ARGUMENTS = ["-r", "0.025", "-l", "2", "-c", "0.5", "-t", "0.6", "--check-mesh", "-q"]
# Windows and Linux builds use the same IEEE operations, but the C runtimes' math functions (sqrt is exact; cbrt,
# exp, atan2 may differ in the last bit) can move a vertex by a rounding step, which smoothing spreads.
TOLERANCE = 1e-5


def read_ply(path):
    """Vertices (list of xyz) and triangles of a binary little-endian PLY written by meniscus (float properties)."""
    data = pathlib.Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    vertex_count = int(next(line.split()[2] for line in header if line.startswith("element vertex")))
    face_count = int(next(line.split()[2] for line in header if line.startswith("element face")))
    in_vertex = False
    properties = 0
    for line in header:
        if line.startswith("element"):
            in_vertex = line.startswith("element vertex")
        elif line.startswith("property") and in_vertex:
            properties += 1
    stride = 4 * properties
    vertices = [struct.unpack_from("<3f", data, end + i * stride) for i in range(vertex_count)]
    offset = end + vertex_count * stride
    triangles = []
    for i in range(face_count):
        count, a, b, c = struct.unpack_from("<B3i", data, offset + i * 13)
        assert count == 3
        triangles.append((a, b, c))
    return vertices, triangles


def compare(linux_ply, windows_ply, label):
    linux_vertices, linux_triangles = read_ply(linux_ply)
    windows_vertices, windows_triangles = read_ply(windows_ply)
    if linux_triangles != windows_triangles or len(linux_vertices) != len(windows_vertices):
        raise SystemExit(f"{label}: the build under test gave {len(windows_vertices)} vertices / {len(windows_triangles)} triangles, "
                         f"Linux {len(linux_vertices)} / {len(linux_triangles)} (or other connectivity)")
    extent = max(max(abs(c) for c in v) for v in linux_vertices)
    worst = max(max(abs(a - b) for a, b in zip(u, v)) for u, v in zip(linux_vertices, windows_vertices))
    if worst > TOLERANCE * extent:
        raise SystemExit(f"{label}: vertices differ by up to {worst:.3g} (tolerance {TOLERANCE * extent:.3g})")
    print(f"{label}: {len(windows_vertices)} vertices, {len(windows_triangles)} triangles; identical connectivity, "
          f"largest vertex difference {worst:.3g}")


def run(command, environment=None):
    completed = subprocess.run(command, capture_output=True, text=True, env=environment)
    if completed.returncode != 0:
        raise SystemExit(f"{' '.join(map(str, command))} exited {completed.returncode}:\n{completed.stdout}{completed.stderr}")
    return completed


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--wine", help="run the other build through this loader (Wine)")
    parser.add_argument("--windows-cli", required=True, help="the command line to check")
    parser.add_argument("--linux-cli", required=True, help="the reference: the Linux GCC build")
    parser.add_argument("--label", default="Windows")
    args = parser.parse_args()
    other = [args.wine, args.windows_cli] if args.wine else [args.windows_cli]
    # Wine decodes the Unix command line in the locale's encoding: make it UTF-8 whatever the machine's default.
    environment = dict(os.environ, LC_ALL="C.UTF-8", LANG="C.UTF-8")

    with tempfile.TemporaryDirectory(prefix="meniscus_windows_") as folder:
        folder = pathlib.Path(folder)
        linux_ply = folder / "linux.ply"
        run([args.linux_cli, "reconstruct", str(FRAME), "-o", str(linux_ply), *ARGUMENTS])

        windows_ply = folder / "windows.ply"
        run([*other, "reconstruct", str(FRAME), "-o", str(windows_ply), *ARGUMENTS], environment)
        compare(linux_ply, windows_ply, "shared frame")

        # A sequence in a folder and under names with non-ASCII characters, read and written by the Windows build.
        unicode_folder = folder / "été 粒子"
        unicode_folder.mkdir()
        for frame in (1, 2):
            shutil.copy(FRAME, unicode_folder / f"flüssigkeit_{frame:04d}.vtk")
        pattern = str(unicode_folder / "flüssigkeit_{}.vtk")
        output = str(unicode_folder / "oberfläche_{}.ply")
        stats = unicode_folder / "statistik.json"
        run([*other, "reconstruct", pattern, "-o", output, "--stats", str(stats), *ARGUMENTS], environment)
        for frame in (1, 2):
            written = unicode_folder / f"oberfläche_{frame:04d}.ply"
            if not written.exists():
                raise SystemExit(f"the {args.label} build did not write {written}")
            compare(linux_ply, written, f"non-ASCII path, frame {frame}")
        if "flüssigkeit_0001.vtk" not in stats.read_text(encoding="utf-8"):
            raise SystemExit("the statistics file does not name the input as given")
    print(f"{args.label} command line matches the Linux GCC build")


if __name__ == "__main__":
    sys.exit(main())
