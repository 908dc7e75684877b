"""Sweeps the iso threshold and a cut at Mantaflow's walls over baked Mantaflow scenes: the enclosed volume of the
pipeline's surface (Python API, r = dx / 2, the cache's domain with Blender's default band) against Mantaflow's own
mesh's (scene.json), every frame; prints each setting's min / max ratio per scene and writes every ratio as JSON.

    OMP_WAIT_POLICY=PASSIVE python3 bench/mantaflow_volume_sweep.py BAKES_DIR OUT.json [--scenes pool_UNI,...]
        [--iso 0.45,0.43,0.42,0.40] [--threads 1]

The cut is the container (mesh_aabb_min / max): the domain's box inset by 0.8 cell on its closed sides, where
Mantaflow's mesh ends (its outer cell layer is set to phi = 0.5 before marching cubes)."""
import argparse
import json
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
import meniscus  # noqa: E402

WALL_INSET_CELLS = 0.8


def enclosed_volume(mesh):
    vertices = np.asarray(mesh.vertices, dtype=float)
    triangles = np.asarray(mesh.all_triangles())
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    return np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0


def cut_box(domain):
    """World box of an axis-aligned domain, inset on its closed sides (order -x, +x, -y, +y, -z, +z)."""
    origin = np.asarray(domain["origin"], dtype=float)
    cell = np.array([np.linalg.norm(axis) for axis in domain["axes"]])
    extent = cell * np.asarray(domain["resolution"])
    closed = domain.get("closed_borders", [True] * 6)
    low, high = origin.copy(), origin + extent
    for axis in range(3):
        if closed[2 * axis]:
            low[axis] += WALL_INSET_CELLS * cell[axis]
        if closed[2 * axis + 1]:
            high[axis] -= WALL_INSET_CELLS * cell[axis]
    return low.tolist(), high.tolist()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("bakes")
    parser.add_argument("out")
    parser.add_argument("--scenes", default="pool_UNI,open_top_UNI,moving_obstacle_UNI,splash_UNI")
    parser.add_argument("--iso", default="0.45,0.43,0.42,0.40")
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    bakes = pathlib.Path(args.bakes)
    isos = [float(x) for x in args.iso.split(",")]
    results = {}
    for scene in args.scenes.split(","):
        info = json.loads((bakes / scene / "scene.json").read_text())
        reference = {int(f): v for f, v in info["mantaflow_mesh_volume"].items()}
        ratios = {f"{iso}/{cut}": {} for iso in isos for cut in ("none", "walls")}
        started = time.perf_counter()
        for frame in sorted(reference):
            particles = meniscus.read_particles(bakes / scene / f"cache/data/pp_{frame:04d}.uni")
            domain = {**particles.fluid_domain, "band_width_cells": info["particle_band_width"]}
            cell = float(np.linalg.norm(domain["axes"][0]))
            if info.get("open_top"):
                domain["closed_borders"] = [True] * 5 + [False]
            low, high = cut_box(domain)
            for iso in isos:
                for cut in ("none", "walls"):
                    box = {"mesh_aabb_min": low, "mesh_aabb_max": high} if cut == "walls" else {}
                    mesh = meniscus.reconstruct(particles.positions, cell / 2, fluid_domain=domain, iso_threshold=iso,
                                                threads=args.threads, **box)
                    ratios[f"{iso}/{cut}"][frame] = enclosed_volume(mesh) / reference[frame]
        results[scene] = ratios
        print(f"{scene}: {len(reference)} frames in {time.perf_counter() - started:.0f} s", flush=True)
        for key, per_frame in ratios.items():
            values = np.array(list(per_frame.values()))
            after_first = np.array([r for f, r in per_frame.items() if f != 1])
            print(f"  iso {key:12s} min {values.min():.3f} max {values.max():.3f}"
                  f"  (frames 2+: {after_first.min():.3f}-{after_first.max():.3f})", flush=True)
        pathlib.Path(args.out).write_text(json.dumps(results, indent=1))


main()
