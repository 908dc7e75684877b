"""Compute time of the Windows build under Wine against the Linux build, same frame, same thread count:

    python3 bench/windows_wine.py [--repetitions 5]     (needs build/ and build-windows/: scripts/build_windows.sh)

Runs the two command lines alternately, each in a fresh process, and takes each run's per-stage seconds from its
--stats file: compute = total - read - write (the reconstruction itself, what Wine could slow down through its
threads and memory calls). Writes bench/results/windows_wine.md and prints it.
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
FRAME = ROOT.parent / "shared" / "data" / "splashsurf" / "double_dam_break_frame_26_4732_particles.vtk"
ARGUMENTS = ["-r", "0.025", "-l", "2", "-c", "0.5", "-t", "0.6", "-q"]


def compute_seconds(command, folder, environment, threads):
    stats = folder / "stats.json"
    subprocess.run([*command, "reconstruct", str(FRAME), "-o", str(folder / "out.ply"), "--stats", str(stats),
                    "-n", str(threads), *ARGUMENTS], check=True, input="", capture_output=True, env=environment)
    seconds = json.loads(stats.read_text())["frames"][0]["seconds"]
    return seconds["total"] - seconds["read"] - seconds["write"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--repetitions", type=int, default=5)
    args = parser.parse_args()
    prefix = ROOT / "build-windows" / "wineprefix"
    environment = dict(os.environ, WINEPREFIX=str(prefix), WINEDEBUG="-all")
    linux = [str(ROOT / "build" / "bin" / "meniscus")]
    windows = ["/usr/lib/wine/wine64", str(ROOT / "build-windows" / "bin" / "meniscus.exe")]
    rows = []
    loads = [os.getloadavg()[0]]  # a shared machine: the figures mean little without it
    with tempfile.TemporaryDirectory() as folder:
        folder = pathlib.Path(folder)
        for threads in (1, 2):
            times = {"linux": [], "windows": []}
            for _ in range(args.repetitions):
                for name, command in (("linux", linux), ("windows", windows)):
                    times[name].append(compute_seconds(command, folder, environment, threads))
                loads.append(os.getloadavg()[0])
            linux_median, windows_median = statistics.median(times["linux"]), statistics.median(times["windows"])
            rows.append(f"| {threads} | {linux_median:.3f} s | {windows_median:.3f} s | {windows_median / linux_median:.2f}x |")
    table = "\n".join([
        f"Windows build (mingw-w64, under Wine 8.0) against the Linux build (GCC 12), {FRAME.name}, "
        f"{' '.join(ARGUMENTS[:-1])}; compute seconds (total - read - write from --stats), medians of "
        f"{args.repetitions}, runs alternating; OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY', '(unset)')}, "
        f"1-minute load average {min(loads):.1f}-{max(loads):.1f} on {os.cpu_count()} cores. "
        "`python3 bench/windows_wine.py`",
        "",
        "| threads | Linux | Windows under Wine | Windows / Linux |",
        "|---:|---:|---:|---:|",
        *rows, ""])
    (ROOT / "bench" / "results" / "windows_wine.md").write_text(table)
    print(table)


if __name__ == "__main__":
    main()
