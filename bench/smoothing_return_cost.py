"""The physical-reach smoothing's heat stage alone at 1 M particles, its local return low-passed on the mesh
(aggregate_size=0, as before the aggregates) and on surface aggregates (the pipeline's choice up to c ~ 0.9):
seconds per part of the stage (flow, return, final correction) and operator applications, best of 3, alternating,
in one process on one unsmoothed decimated mesh per cube size.

    python3 bench/generate_frame.py --particles 1000000 --output build/bench/generated_1M.vtk
    build/venv-bench/bin/python bench/smoothing_return_cost.py
Writes bench/results/smoothing/return_cost_1M.json.
"""
import json
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
import meniscus  # noqa: E402
from meniscus import _core  # noqa: E402

R, REACH, THREADS = 0.025, 4.28, 2


def main():
    positions = meniscus.read_particles(str(ROOT / "build" / "bench" / "generated_1M.vtk")).positions
    results = {}
    for cube in (0.5, 0.25):
        mesh = meniscus.reconstruct(positions, R, cube_size=cube, smoothing_iterations=0, output_weights=True, normals=False,
                                    threads=THREADS)
        vertices = np.ascontiguousarray(mesh.vertices, np.float32)
        triangles = np.ascontiguousarray(mesh.triangles, np.int32)
        weights = mesh.attributes["weights"]
        for _ in range(3):
            for name, aggregate_size in (("mesh", 0.0), ("aggregates", -1.0)):
                start = time.perf_counter()
                _, info = _core.heat_smooth(vertices, triangles, weights, reach=REACH * R, particle_radius=R,
                                            aggregate_size=aggregate_size, threads=THREADS)
                seconds = time.perf_counter() - start
                key = f"c={cube}, return on {name}"
                if key not in results or seconds < results[key]["seconds"]:
                    results[key] = dict(seconds=seconds, vertices=len(vertices), applications=info["applications"],
                                        coarse_applications=info["coarse_applications"], aggregates=info["aggregates"],
                                        **{f"seconds_{k}": v for k, v in info["seconds"].items()})
                print(key, json.dumps(results[key]), flush=True)
    out = ROOT / "bench" / "results" / "smoothing" / "return_cost_1M.json"
    out.write_text(json.dumps(dict(threads=THREADS, reach=REACH, best_of=3, runs=results), indent=1) + "\n")


if __name__ == "__main__":
    main()
