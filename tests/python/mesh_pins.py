"""Checksums of the meshes the pipeline makes from every shared frame, to prove a refactor keeps behaviour.

    python3 tests/python/mesh_pins.py --write      (re-pins: only when an output change is intended, and said so)

tests/python/test_mesh_pins.py recomputes them and compares with tests/data/mesh_pins.json. A checksum covers the
vertices, triangles, normals and interpolated attributes bit for bit; each case spells out every parameter, so that
a change of defaults does not move a pin. The cases run with 1 and 2 threads in the test (the output must not
depend on the thread count).
"""
import argparse
import hashlib
import json
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared" / "data" / "splashsurf"
PINS = ROOT / "tests" / "data" / "mesh_pins.json"
FRAMES = sorted(p.name for p in SHARED.glob("*") if p.suffix in (".vtk", ".bgeo"))

FULL = dict(particle_radius=0.025, smoothing_length=2.0, cube_size=0.5, iso_threshold=0.6, mesh_cleanup=False,
            decimate_barnacles=True, smoothing_iterations=25, smoothing_strength=1.0, smoothing_reach=0.0,
            smoothing_weights=True, weights_normalization=0.0, volume_restoration=True, normals=True,
            normal_smoothing_iterations=10, sph_normals=False)
CASES = {
    "full c=0.5": FULL,
    "full c=1.0": dict(FULL, cube_size=1.0),
    "raw marching cubes c=0.75": dict(FULL, cube_size=0.75, decimate_barnacles=False, smoothing_iterations=0,
                                      normal_smoothing_iterations=0),
    "cleanup, uniform smoothing, SPH normals c=1.0": dict(FULL, cube_size=1.0, mesh_cleanup=True,
                                                          decimate_barnacles=False, smoothing_weights=False,
                                                          volume_restoration=False, sph_normals=True),
    # The heat flow of a physical reach (post/heat_smoothing.h; the default since issue 12), at c = 1.0 where it grows.
    "physical-reach smoothing 4.28 r c=1.0": dict(FULL, cube_size=1.0, smoothing_reach=4.28),
}


def checksum(mesh):
    digest = hashlib.sha256()
    for array in (mesh.vertices, mesh.triangles, mesh.normals):
        digest.update(b"-" if array is None else np.ascontiguousarray(array).tobytes())
    for name in sorted(mesh.attributes):
        digest.update(name.encode())
        digest.update(np.ascontiguousarray(mesh.attributes[name], dtype=np.float32).tobytes())
    return digest.hexdigest()[:24]


def compute(meniscus, threads=0):
    pins = {}
    for frame in FRAMES:
        particles = meniscus.read_particles(SHARED / frame)
        # Interpolated (float) attributes only: particle ids are carried from the nearest particle since 0.2.
        attributes = {k: v for k, v in particles.attributes.items() if k != "id"}
        for case, parameters in CASES.items():
            mesh = meniscus.reconstruct(particles.positions, attributes=attributes, threads=threads, **parameters)
            pins[f"{frame} | {case}"] = f"{checksum(mesh)} {len(mesh.vertices)} {len(mesh.triangles)}"
    return pins


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", action="store_true")
    parser.add_argument("--package", default=str(ROOT / "build" / "python"), help="folder holding the meniscus package")
    args = parser.parse_args()
    sys.path.insert(0, args.package)
    import meniscus

    pins = compute(meniscus)
    if args.write:
        PINS.write_text(json.dumps(pins, indent=1, sort_keys=True) + "\n")
        print(f"wrote {len(pins)} pins to {PINS}")
    else:
        print(json.dumps(pins, indent=1, sort_keys=True))


if __name__ == "__main__":
    main()
