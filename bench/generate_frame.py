"""Generates a dam-break-like particle frame for benchmarks: a dense block with jitter, a thin splash sheet and
scattered droplets, on the 2r lattice of SPlisHSPlasH-like data. Writes legacy VTK (binary, big-endian).

    python3 bench/generate_frame.py --particles 1000000 --output build/bench/generated_1M.vtk
"""
from __future__ import annotations

import argparse
import math
import pathlib

try:
    import numpy as np
except ImportError:  # layout() serves bench/scaling.py's plain-Python copy of the recipe without it
    np = None


def layout(count: int, radius: float = 0.025):
    """The recipe's sizes: spacing, block, sheet and droplet counts, the block's lattice (nx, ny, nz), the sheet's side."""
    spacing = 2.0 * radius
    block_count = int(count * 0.95)
    sheet_count = int(count * 0.04)
    droplet_count = count - block_count - sheet_count
    # Block: a box twice as long as it is wide and high, on the lattice.
    side = int(round((block_count / 2.0) ** (1.0 / 3.0)))
    nx, ny = 2 * side, side
    nz = max(1, -(-block_count // (nx * ny)))
    return spacing, block_count, sheet_count, droplet_count, (nx, ny, nz), int(math.sqrt(sheet_count / 2.0))


def generate(count: int, radius: float = 0.025, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    spacing, block_count, sheet_count, droplet_count, (nx, ny, nz), sheet_side = layout(count, radius)
    # Block: jittered by 10 % of the spacing.
    grid = np.stack(np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij"), axis=-1).reshape(-1, 3)
    block = (grid[:block_count] + 0.5) * spacing + rng.normal(0.0, 0.1 * spacing, (block_count, 3))
    # Sheet: two layers thick, curling up from the block's far end.
    u, v = np.meshgrid(np.arange(sheet_side), np.arange(sheet_side), indexing="ij")
    u, v = u.ravel() * spacing, v.ravel() * spacing
    angle = u / (sheet_side * spacing) * 1.2
    sheet_layers = []
    for layer in range(2):
        r = 0.8 * nz * spacing + layer * spacing
        sheet_layers.append(np.stack([nx * spacing + r * np.sin(angle), v * ny / sheet_side, r * (1.0 - np.cos(angle)) + 0.2 * nz * spacing], axis=1))
    sheet = np.concatenate(sheet_layers) + rng.normal(0.0, 0.05 * spacing, (2 * len(u), 3))
    # Droplets: singles and small clusters above the block.
    centres = rng.uniform([0, 0, nz * spacing * 1.2], [nx * spacing * 1.3, ny * spacing, nz * spacing * 2.0], (droplet_count, 3))
    cluster = rng.integers(0, 4, droplet_count)  # every few particles sit next to the previous one
    droplets = centres.copy()
    droplets[1:][cluster[1:] > 0] = centres[:-1][cluster[1:] > 0] + rng.normal(0.0, 0.5 * spacing, (int((cluster[1:] > 0).sum()), 3))
    particles = np.concatenate([block, sheet, droplets]).astype(np.float32)
    return particles[:count]


def write_vtk(path: pathlib.Path, positions: np.ndarray, velocity: np.ndarray = None) -> None:
    """Legacy VTK, binary (big-endian): vertex cells, and a `velocity` point attribute when given."""
    n = len(positions)
    with open(path, "wb") as f:
        f.write(b"# vtk DataFile Version 4.1\nMeniscus generated benchmark frame\nBINARY\nDATASET UNSTRUCTURED_GRID\n")
        f.write(f"POINTS {n} float\n".encode())
        f.write(np.ascontiguousarray(positions, dtype=">f4").tobytes())
        f.write(f"\nCELLS {n} {2 * n}\n".encode())
        cells = np.empty((n, 2), dtype=">i4")
        cells[:, 0] = 1
        cells[:, 1] = np.arange(n)
        f.write(cells.tobytes())
        f.write(f"\nCELL_TYPES {n}\n".encode())
        f.write(np.full(n, 1, dtype=">i4").tobytes())
        if velocity is not None:
            f.write(f"\nPOINT_DATA {n}\nVECTORS velocity float\n".encode())
            f.write(np.ascontiguousarray(velocity, dtype=">f4").tobytes())
        f.write(b"\n")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--particles", type=int, default=1_000_000)
    parser.add_argument("--output", type=pathlib.Path, required=True)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    args.output.parent.mkdir(parents=True, exist_ok=True)
    write_vtk(args.output, generate(args.particles, seed=args.seed))
    print(args.output)
