"""Side by side with the reference implementation (pysplashsurf, PyPI): the same frames, the same parameters, the
same machine and threads; both meshes measured with the same quality report (meniscus.assess_quality).

    bash bench/compare_splashsurf.sh            # sets up a venv with pysplashsurf, then runs this script
Writes bench/results/compare_splashsurf.md (and .json).
"""
import argparse
import json
import pathlib
import statistics
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
import meniscus  # noqa: E402
import pysplashsurf  # noqa: E402

from compare import FRAMES  # noqa: E402  (the same seven shared frames)
PARAMS = dict(particle_radius=0.025, smoothing_length=2.0, cube_size=0.5, iso_threshold=0.6)


def run_meniscus(positions):
    mesh = meniscus.reconstruct(positions, PARAMS["particle_radius"], smoothing_length=PARAMS["smoothing_length"],
                                cube_size=PARAMS["cube_size"], iso_threshold=PARAMS["iso_threshold"],
                                decimate_barnacles=True, smoothing_iterations=25, normal_smoothing_iterations=10,
                                keep_raw_mesh=True)
    return mesh.vertices, mesh.triangles, mesh.raw.vertices, mesh.raw.triangles


def run_splashsurf(positions):
    result, reconstruction = pysplashsurf.reconstruction_pipeline(
        positions, particle_radius=PARAMS["particle_radius"], smoothing_length=PARAMS["smoothing_length"],
        cube_size=PARAMS["cube_size"], iso_surface_threshold=PARAMS["iso_threshold"], decimate_barnacles=True,
        mesh_smoothing_iters=25, mesh_smoothing_weights=True, compute_normals=True, normals_smoothing_iters=10,
        output_raw_mesh=True, multi_threading=True)
    mesh, raw = result.mesh, reconstruction.mesh
    return mesh.vertices, mesh.triangles, raw.vertices, raw.triangles


def quality(vertices, triangles):
    mesh = meniscus.Mesh(np.ascontiguousarray(vertices, dtype=np.float32), np.ascontiguousarray(triangles, dtype=np.int32))
    return meniscus.assess_quality(mesh)


def droplet_volume(q, largest):
    return sum(v for _, v in q["components"] if 0 < v < 0.01 * largest)


def measure(name, run, positions, repetitions):
    times = []
    for _ in range(repetitions):
        start = time.perf_counter()
        vertices, triangles, raw_vertices, raw_triangles = run(positions)
        times.append(time.perf_counter() - start)
    q, raw = quality(vertices, triangles), quality(raw_vertices, raw_triangles)
    largest = raw["components"][0][1] if raw["components"] else 1.0
    raw_droplets = droplet_volume(raw, largest)
    return {
        "tool": name,
        "seconds": statistics.median(times),
        "triangles": q["triangles"],
        "ok": q["check"]["ok"],
        "volume_ratio": q["volume"] / raw["volume"],
        "bumpiness_ratio": q["bumpiness"] / raw["bumpiness"],
        "bumpiness": q["bumpiness"],
        "normal_angle": q["mean_normal_angle_deg"],
        "droplet_volume_ratio": droplet_volume(q, largest) / raw_droplets if raw_droplets > 0 else None,
        "components": [len(raw["components"]), len(q["components"])],
        "barnacles": q["single_vertex_configurations"] + q["double_vertex_configurations"],
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--data", type=pathlib.Path, default=ROOT.parent / "shared" / "data" / "splashsurf")
    parser.add_argument("--repetitions", type=int, default=3)
    parser.add_argument("--output", type=pathlib.Path, default=ROOT / "bench" / "results" / "compare_splashsurf")
    args = parser.parse_args()
    rows = []
    for frame in FRAMES:
        positions = meniscus.read_particles(args.data / frame).positions
        # Alternate the tools so that neither always runs on a warmer machine.
        ours = measure("meniscus", run_meniscus, positions, args.repetitions)
        theirs = measure("pysplashsurf", run_splashsurf, positions, args.repetitions)
        rows.append({"frame": frame, "particles": len(positions), "meniscus": ours, "pysplashsurf": theirs})
        print(frame, json.dumps(ours), json.dumps(theirs), flush=True)
    args.output.with_suffix(".json").write_text(json.dumps(rows, indent=1))

    def fmt(x, spec=".3f"):
        return "–" if x is None else format(x, spec)

    lines = [
        "# Meniscus vs pysplashsurf: full pipeline, shared frames",
        "",
        f"r = {PARAMS['particle_radius']}, l = {PARAMS['smoothing_length']}, c = {PARAMS['cube_size']}, t = {PARAMS['iso_threshold']}; "
        "barnacle decimation, 25 weighted smoothing iterations, normals with 10 smoothing iterations; both tools on all "
        f"cores of this machine, median of {args.repetitions} runs. Quality measured on both meshes with `meniscus inspect`'s "
        "report: volume and bumpiness relative to each tool's own raw marching-cubes mesh; droplets = positive components "
        "under 1 % of the largest one's volume.",
        "",
        "| frame | particles | tool | time (s) | triangles | closed+manifold | volume / raw | bumpiness / raw | droplet volume kept | barnacles left |",
        "|---|---:|---|---:|---:|---|---:|---:|---:|---:|",
    ]
    for row in rows:
        for tool in ("meniscus", "pysplashsurf"):
            r = row[tool]
            lines.append(f"| {row['frame'].split('_particles')[0]} | {row['particles']} | {tool} | {r['seconds']:.3f} | {r['triangles']} | "
                         f"{'yes' if r['ok'] else 'NO'} | {fmt(r['volume_ratio'], '.4f')} | {fmt(r['bumpiness_ratio'])} | "
                         f"{fmt(r['droplet_volume_ratio'])} | {r['barnacles']} |")
    args.output.with_suffix(".md").write_text("\n".join(lines) + "\n")
    print(args.output.with_suffix(".md"))


if __name__ == "__main__":
    main()
