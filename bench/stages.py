"""Per-stage time and peak memory of the CLI on the shared frames and on a generated 1 M-particle frame.

    bash bench/stages.sh              # builds, generates the frame, runs, writes bench/results/stages.md
Each frame runs in its own process (so peak memory is that frame's), with 1 and 2 threads, full pipeline
(decimation, weights, 25 smoothing iterations, normals with 10 smoothing iterations) and reconstruction only.
"""
import argparse
import json
import pathlib
import subprocess
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
CLI = ROOT / "build" / "bin" / "meniscus"
SHARED = ROOT.parent / "shared" / "data" / "splashsurf"
RECONSTRUCTION_ONLY = ["--mesh-smoothing-iters", "0", "--decimate-barnacles", "off", "--normals-smoothing-iters", "0"]


def run(frame: pathlib.Path, threads: int, cube: float, extra):
    with tempfile.TemporaryDirectory() as tmp:
        stats = pathlib.Path(tmp) / "stats.json"
        subprocess.run([str(CLI), "reconstruct", str(frame), "-o", str(pathlib.Path(tmp) / "out.ply"), "-r", "0.025", "-l", "2",
                        "-c", str(cube), "--threads", str(threads), "--stats", str(stats), "-q", *extra], check=True)
        return json.loads(stats.read_text())["frames"][0]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--generated", type=pathlib.Path, default=ROOT / "build" / "bench" / "generated_1M.vtk")
    parser.add_argument("--output", type=pathlib.Path, default=ROOT / "bench" / "results" / "stages")
    args = parser.parse_args()
    frames = sorted(SHARED.glob("*_particles.*")) + [args.generated]
    rows = []
    for frame in frames:
        for mode, extra in (("full", []), ("reconstruction", RECONSTRUCTION_ONLY)):
            for threads in (1, 2):
                record = run(frame, threads, 0.5, extra)
                rows.append({"frame": frame.name, "mode": mode, "threads": threads, **record})
                print(frame.name, mode, threads, round(record["seconds"]["total"], 3), flush=True)
    args.output.with_suffix(".json").write_text(json.dumps(rows, indent=1))
    stages = ["read", "neighborhood", "density", "level set and marching cubes", "decimation", "weights", "smoothing",
              "volume restoration", "normals", "write"]
    lines = ["# Per-stage seconds and peak memory (CLI, r = 0.025, l = 2, c = 0.5, t = 0.6)", "",
             "Full pipeline: barnacle decimation, weights, 25 smoothing iterations, volume restoration, normals with 10 "
             "smoothing iterations. Reconstruction: marching cubes and area-weighted normals only. Reproduce: "
             "`bash bench/stages.sh`.", "",
             "| frame | particles | mode | threads | triangles | " + " | ".join(stages) + " | total (s) | peak memory (MiB) |",
             "|---|---:|---|---:|---:|" + "---:|" * len(stages) + "---:|---:|"]
    for r in rows:
        cells = [f"{r['seconds'].get(s, 0.0):.3f}" if s in r["seconds"] else "–" for s in stages]
        lines.append(f"| {r['frame'].split('_particles')[0]} | {int(r['counts']['particles'])} | {r['mode']} | {r['threads']} | "
                     f"{int(r['counts']['triangles'])} | " + " | ".join(cells) +
                     f" | {r['seconds']['total']:.3f} | {r['peak_memory_bytes'] / 2**20:.0f} |")
    args.output.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print(args.output.with_suffix(".md"))


if __name__ == "__main__":
    main()
