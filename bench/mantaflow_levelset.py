"""A numpy prototype of the surface Mantaflow meshes (the product: native/core/surface/particle_level_set.cpp,
fluid_surface), rebuilt from a cache's FLIP particles alone: does Mantaflow's own particle level set, at its defaults,
reproduce the volume of Mantaflow's mesh (scene.json) frame by frame? It says whether the gap between our surface and
Mantaflow's is reachable from the particles.

Mantaflow's mesh step (Blender's liquid_script.h, Mantaflow's flip.cpp), as rebuilt here, in the mesh grid (the
domain's grid refined by the Mesh panel's Upres Factor, Blender's default 2; lengths in its cells):
  - improved particle level set (Zhu-Bridson averaging, Solenthaler's correction): radius R = 0.5 sqrt(3) (2.0 + 0.01)
    (Mesh "Particle Radius" 2.0 and Mantaflow's 1 % margin); per cell centre x, the particles in the cells up to
    int(R) + 1 away weighted w = max(0, 1 - |x - p|^2 / (4 R^2)); phi = |x - mean p| - R; where the mean position's
    Jacobian has its largest eigenvalue over 0.4 the radius is scaled down (to 0 at 3.5, smoothstep), phi capped at R;
  - one 7-point smoothing pass, then one that only lowers (smoothen pos / neg 1 / 1), phi = 0.5 on the outer layer;
  - joined (min) with the simulation's level set + 1 cell ("shrink slightly"); that level set is not in the cache.
    --fill stands in for it: the cells that air from the domain's top cannot reach without passing within 1.5 domain
    cells of a particle or through the scene's obstacle (the box of tests/mantaflow/bake_scene.py), kept 1 cell
    inside that closure (Mantaflow's shrink), get phi = -1 (without --fill a pool's interior is hollow);
  - extrapolateLsSimple inside (band + 2 cells) and outside (3): deeper cells take their neighbours' value -1 cell,
    the first layer keeps its own (what sets where the surface meets the walls);
  - phi = 0.5 on the outer Upres Factor layers (setBound), marching cubes (skimage) at 0.

    python3 bench/mantaflow_levelset.py BAKES_DIR [--scenes pool_UNI,splash_UNI] [--frames 1-24] [--fill]
        [--upres 2] [--radius-factor 2.0] [--json OUT]
Needs numpy, scipy and scikit-image (e.g. a venv with --system-site-packages and pip install scikit-image)."""
import argparse
import json
import pathlib
import sys
import time

import numpy as np
from scipy import ndimage
from skimage import measure

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "build" / "python"))
import meniscus  # noqa: E402

CONCAVE_LOWER, CONCAVE_UPPER = 0.4, 3.5
# How far (domain cells) a particle seals the shell against air for --fill: at 1 cell the falling sphere's sparse
# band at frame 1 leaks (moving_obstacle 0.940, check48 0.900), at 1.5 it holds (1.000, 0.999).
CLOSING_CELLS = 1.5


def averaged_levelset(grid_positions, shape, radius):
    """phi, the weighted mean position per cell and where any particle weighed (Mantaflow's averaged weights)."""
    shape = np.asarray(shape)
    cells = np.clip(np.floor(grid_positions).astype(np.int64), 0, shape - 1)
    reach = int(radius) + 1
    weight = np.zeros(int(np.prod(shape)))
    mean = np.zeros((int(np.prod(shape)), 3))
    inverse = 1.0 / (4.0 * radius * radius)
    offsets = range(-reach, reach + 1)
    for dx in offsets:
        for dy in offsets:
            for dz in offsets:
                target = cells + np.array([dx, dy, dz])
                inside = np.all((target >= 0) & (target < shape), axis=1)
                target, points = target[inside], grid_positions[inside]
                w = np.maximum(0.0, 1.0 - ((target + 0.5 - points) ** 2).sum(axis=1) * inverse)
                flat = np.ravel_multi_index(target.T, shape)
                weight += np.bincount(flat, w, minlength=weight.size)
                for axis in range(3):
                    mean[:, axis] += np.bincount(flat, w * points[:, axis], minlength=weight.size)
    weighed = weight > 1e-6
    mean[weighed] /= weight[weighed, None]
    mean[~weighed] = 0.0  # Mantaflow's saved mean stays 0 where nothing weighed; the Jacobian sees that edge
    centres = np.stack(np.meshgrid(*[np.arange(n) + 0.5 for n in shape], indexing="ij"), axis=-1).reshape(-1, 3)
    phi = np.full(weight.size, radius)
    phi[weighed] = np.linalg.norm(centres[weighed] - mean[weighed], axis=1) - radius
    return phi.reshape(shape), mean.reshape(*shape, 3), weighed.reshape(shape), centres.reshape(*shape, 3)


def corrected_levelset(phi, mean, weighed, centres, radius):
    """Solenthaler's correction where the mean position spreads (concave regions), inner cells only."""
    phi = phi.copy()
    inner = np.zeros_like(weighed)
    inner[1:-1, 1:-1, 1:-1] = True
    todo = weighed & inner
    index = np.nonzero(todo)
    jacobian = np.empty((len(index[0]), 3, 3))
    for column in range(3):
        step = np.zeros(3, dtype=int)
        step[column] = 1
        ahead = mean[index[0] + step[0], index[1] + step[1], index[2] + step[2]]
        behind = mean[index[0] - step[0], index[1] - step[1], index[2] - step[2]]
        jacobian[:, :, column] = 0.5 * (ahead - behind)
    largest = np.linalg.eigvals(jacobian).real.max(axis=1)
    t = (CONCAVE_UPPER - largest) / (CONCAVE_UPPER - CONCAVE_LOWER)
    correction = np.where(largest >= CONCAVE_LOWER, t ** 3 - 3 * t ** 2 + 3 * t, 1.0)
    correction = np.clip(correction, 0.0, 1.0)
    corrected = np.linalg.norm(centres[index] - mean[index], axis=1) - radius * correction
    phi[index] = np.minimum(corrected, radius)
    return phi


def seven_point_average(phi):
    out = np.zeros_like(phi)  # Mantaflow's fresh grid: its outer layer stays 0
    c = phi[1:-1, 1:-1, 1:-1]
    out[1:-1, 1:-1, 1:-1] = (c + phi[2:, 1:-1, 1:-1] + phi[:-2, 1:-1, 1:-1] + phi[1:-1, 2:, 1:-1] + phi[1:-1, :-2, 1:-1]
                             + phi[1:-1, 1:-1, 2:] + phi[1:-1, 1:-1, :-2]) / 7.0
    return out


def smoothed(phi):
    first = seven_point_average(phi)
    second = seven_point_average(first)
    out = phi.copy()
    inner = (slice(1, -1),) * 3
    out[inner] = np.where(second[inner] < phi[inner], second[inner], first[inner])
    return out


def set_bound(phi, value, width):
    phi = phi.copy()
    for axis in range(3):
        low = [slice(None)] * 3
        low[axis] = slice(0, width + 1)
        high = [slice(None)] * 3
        high[axis] = slice(phi.shape[axis] - 1 - width, None)
        phi[tuple(low)] = value
        phi[tuple(high)] = value
    return phi


def enclosed_cells(grid_positions, shape, margin, reach, shrink, solid):
    """Cells no path from the domain's top reaches without passing within `reach` cells of a particle (a band of
    jittered particles has gaps the particle level set alone would leak through), more than reach + shrink cells
    from such a path (the closure taken back by reach, then shrunk as Mantaflow shrinks its grid level set)."""
    occupied = np.zeros(shape, dtype=bool)
    cells = np.clip(np.floor(grid_positions).astype(np.int64), 0, np.asarray(shape) - 1)
    occupied[tuple(cells.T)] = True
    shell = ndimage.distance_transform_edt(~occupied) <= reach
    inner = np.zeros(shape, dtype=bool)
    inner[margin:-margin, margin:-margin, margin:-margin] = True
    # Air passes neither through an obstacle nor through a gap between it and the nearest particles.
    blocked = ndimage.distance_transform_edt(~solid) <= reach
    labels, _ = ndimage.label(~shell & inner & ~blocked)
    top = np.unique(labels[:, :, -margin - 1])
    air = np.isin(labels, top[top > 0])
    return ~(ndimage.distance_transform_edt(~air) <= reach + shrink) & inner & ~solid


NEIGHBOURS = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]


def shifted(array, step, fill):
    """array moved so that out[p] = array[p + step], `fill` beyond the grid."""
    out = np.full_like(array, fill)
    source = tuple(slice(max(s, 0), array.shape[a] + min(s, 0)) for a, s in enumerate(step))
    target = tuple(slice(max(-s, 0), array.shape[a] + min(-s, 0)) for a, s in enumerate(step))
    out[target] = array[source]
    return out


def extrapolated(phi, distance, inside):
    """Mantaflow's extrapolateLsSimple: the first layer across the surface keeps its value, the next layers (up to
    `distance`) take their nearer neighbours' mean plus one cell, the rest +-(distance + 2); outer layer untouched."""
    phi = phi.copy()
    direction = -1.0 if inside else 1.0
    inner = np.zeros(phi.shape, dtype=bool)
    inner[1:-1, 1:-1, 1:-1] = True
    layer = np.zeros(phi.shape, dtype=np.int32)
    layer[inner & ((phi > 0) if inside else (phi < 0))] = 1
    first = np.zeros(phi.shape, dtype=bool)
    for step in NEIGHBOURS:
        first |= shifted(layer, step, 0) == 1
    layer[inner & (layer == 0) & first] = 2
    for d in range(2, distance + 1):
        total = np.zeros_like(phi)
        count = np.zeros(phi.shape, dtype=np.int32)
        for step in NEIGHBOURS:
            at_d = shifted(layer, step, 0) == d
            total += np.where(at_d, shifted(phi, step, 0.0), 0.0)
            count += at_d
        todo = inner & (layer == 0) & (count > 0)
        phi[todo] = total[todo] / count[todo] + direction
        layer[todo] = d + 1
    phi[inner & (layer == 0)] = direction * (distance + 2)
    return phi


def obstacle_mask(domain_info, shape, cell, origin, frame, frames):
    """The test scenes' box obstacle (bake_scene.py), in mesh-grid cells: 0.4 m at (0.5, 0.3, 0.25), or keyed from
    (0.6, -0.5) to (-0.6, 0.5) with Blender's default easing."""
    scene = domain_info["scene"]
    if scene == "splash":
        return np.zeros(shape, dtype=bool)
    centre = np.array([0.5, 0.3, 0.25])
    if scene == "moving_obstacle":
        u = (frame - 1) / (frames - 1)
        ease = 3 * u * u - 2 * u ** 3
        centre = np.array([0.6 - 1.2 * ease, -0.5 + 1.0 * ease, 0.25])
    centres = np.stack(np.meshgrid(*[origin[a] + (np.arange(shape[a]) + 0.5) * cell for a in range(3)], indexing="ij"),
                       axis=-1)
    return np.all(np.abs(centres - centre) <= 0.2, axis=-1)


def mantaflow_phi(positions, domain, info, frame, upres, radius_factor, fill, shrink):
    """The mesh grid's level set as Mantaflow meshes it, and the grid's cell edge."""
    base_cell = np.linalg.norm(domain["axes"][0])
    cell = base_cell / upres
    origin = np.asarray(domain["origin"])
    shape = tuple(int(n) * upres for n in domain["resolution"])
    grid_positions = (np.asarray(positions, dtype=float) - origin) / cell
    radius = 0.5 * np.sqrt(3.0) * (radius_factor + 0.01)
    phi, mean, weighed, centres = averaged_levelset(grid_positions, shape, radius)
    phi = corrected_levelset(phi, mean, weighed, centres, radius)
    phi = set_bound(smoothed(phi), 0.5, 0)
    if fill:
        solid = obstacle_mask(info, shape, cell, origin, frame, info["frames"])
        enclosed = enclosed_cells(grid_positions, shape, 1, CLOSING_CELLS * upres, shrink * upres, solid)
        phi = np.where(enclosed, np.minimum(phi, -1.0), phi)
    band = int(info["particle_band_width"])
    phi = extrapolated(extrapolated(phi, band + 2, inside=True), 3, inside=False)
    return set_bound(phi, 0.5, upres - 1), cell


def surface_mesh(phi, cell, origin):
    """Marching cubes at 0 (values at cell centres), world space."""
    vertices, faces, _, _ = measure.marching_cubes(phi, level=0.0)
    return (vertices + 0.5) * cell + np.asarray(origin), faces


def mesh_volume(vertices, faces):
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    return abs(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def mantaflow_surface_volume(positions, domain, info, frame, upres, radius_factor, fill, shrink):
    phi, cell = mantaflow_phi(positions, domain, info, frame, upres, radius_factor, fill, shrink)
    if phi.min() >= 0:
        return 0.0
    return mesh_volume(*surface_mesh(phi, cell, domain["origin"]))


def frame_range(text):
    first, _, last = text.partition("-")
    return range(int(first), int(last or first) + 1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("bakes")
    parser.add_argument("--scenes", default="pool_UNI,splash_UNI")
    parser.add_argument("--frames", default=None)
    parser.add_argument("--fill", action="store_true")
    parser.add_argument("--shrink", type=float, default=1.0, help="the fill kept this many domain cells inside")
    parser.add_argument("--upres", type=int, default=2)
    parser.add_argument("--radius-factor", type=float, default=2.0)
    parser.add_argument("--json")
    args = parser.parse_args()
    bakes = pathlib.Path(args.bakes)
    results = {}
    for scene in args.scenes.split(","):
        info = json.loads((bakes / scene / "scene.json").read_text())
        reference = {int(f): v for f, v in info["mantaflow_mesh_volume"].items()}
        frames = frame_range(args.frames) if args.frames else sorted(reference)
        started = time.perf_counter()
        ratios = {}
        for frame in frames:
            particles = meniscus.read_particles(bakes / scene / f"cache/data/pp_{frame:04d}.uni")
            volume = mantaflow_surface_volume(particles.positions, particles.fluid_domain, info, frame, args.upres,
                                              args.radius_factor, args.fill, args.shrink)
            ratios[frame] = volume / reference[frame]
            print(f"{scene} {frame:3d} particles {len(particles.positions):6d} Mantaflow {reference[frame]:.4f} "
                  f"prototype {volume:.4f} ({ratios[frame]:.3f})", flush=True)
        values = np.array(list(ratios.values()))
        print(f"{scene}: {values.min():.3f}-{values.max():.3f} in {time.perf_counter() - started:.0f} s", flush=True)
        results[scene] = ratios
    if args.json:
        pathlib.Path(args.json).write_text(json.dumps(results, indent=1))



if __name__ == "__main__":
    main()
