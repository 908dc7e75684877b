"""The Python API of Meniscus, free of bpy: usable from plain Python 3.11 with numpy and inside Blender.

    import meniscus
    particles = meniscus.read_particles("fluid_0010.vtk")
    mesh = meniscus.reconstruct(particles.positions, particle_radius=0.025, cube_size=0.5,
                                smoothing_iterations=25, decimate_barnacles=True,
                                normal_smoothing_iterations=10,
                                attributes={"velocity": particles.attributes["velocity"]})
    mesh.vertices, mesh.triangles, mesh.normals, mesh.attributes["velocity"]
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Optional

import numpy as np

from . import _core

__all__ = ["FormatError", "Mesh", "Particles", "__version__", "assess_quality", "check_mesh", "read_mesh",
           "read_particles", "reconstruct", "write_mesh"]

FormatError = _core.FormatError
__version__ = _core.__version__


@dataclass
class Particles:
    positions: np.ndarray                      # (N, 3) float32
    # (N,) or (N, k): float32, or int32 for whole-number fields of the file (ids, labels)
    attributes: Dict[str, np.ndarray] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.positions)


@dataclass
class Mesh:
    vertices: np.ndarray                       # (V, 3) float32
    triangles: np.ndarray                      # (F, 3) int32, counter-clockwise seen from outside
    normals: Optional[np.ndarray] = None       # (V, 3) float32, unit, outward
    attributes: Dict[str, np.ndarray] = field(default_factory=dict)
    stats: dict = field(default_factory=dict)  # {"seconds": {stage: s}, "counts": {...}, "warnings": [...]}
    raw: Optional["Mesh"] = None               # the marching-cubes mesh, when keep_raw_mesh=True
    weights_normalization: float = 0.0         # N_HS used by the feature weights

    def write(self, path: str) -> None:
        write_mesh(self, path)


def _attribute_array(values) -> np.ndarray:
    """Integer and bool arrays (ids, labels, flags) go to the core as they are, which carries them as whole numbers
    (from the nearest particle, never averaged); anything else as float32 (copied only when it is not already)."""
    values = np.asarray(values)
    if values.dtype.kind in "iub":
        return np.ascontiguousarray(values)
    return np.ascontiguousarray(values, dtype=np.float32)


def _mesh(result: dict) -> Mesh:
    return Mesh(result["vertices"], result["triangles"], result["normals"], result["attributes"])


def read_particles(path) -> Particles:
    """Reads a particle file (legacy VTK, BGEO); raises FormatError naming the file and the fault."""
    data = _core.read_particles(str(path))
    return Particles(data["positions"], data["attributes"])


def reconstruct(positions, particle_radius: float, smoothing_length: float = 2.0, cube_size: float = 0.5,
                iso_threshold: float = 0.6, *, attributes: Optional[Dict[str, np.ndarray]] = None,
                mesh_cleanup: bool = False, mesh_cleanup_snap_distance: float = -1.0, decimate_barnacles: bool = False,
                smoothing_iterations: int = 0, smoothing_beta: float = 1.0, smoothing_weights: bool = True,
                weights_normalization: float = 0.0, weights_smoothstep: bool = True, volume_restoration: bool = True,
                output_weights: bool = False,
                normals: bool = True, normal_smoothing_iterations: int = 0, sph_normals: bool = False,
                threads: int = 0, memory_budget: int = 0, skip_invalid: bool = False,
                keep_raw_mesh: bool = False) -> Mesh:
    """Reconstructs the fluid surface of (N, 3) float32/float64 C-contiguous positions (read without a copy).

    Lengths follow splashsurf: particle_radius is absolute, smoothing_length and cube_size are multiples of it
    (kernel support 2 * smoothing_length * particle_radius). weights_normalization 0 means automatic. Raises
    ValueError naming a bad argument and MemoryError (with the estimate) when the grid exceeds the memory budget.
    """
    converted = {}
    for name, values in (attributes or {}).items():
        converted[str(name)] = _attribute_array(values)
    result = _core.reconstruct(
        positions, float(particle_radius), float(smoothing_length), float(cube_size), float(iso_threshold), converted,
        bool(mesh_cleanup), float(mesh_cleanup_snap_distance), bool(decimate_barnacles), int(smoothing_iterations),
        float(smoothing_beta), bool(smoothing_weights), float(weights_normalization), bool(weights_smoothstep),
        bool(volume_restoration), bool(output_weights), bool(normals), int(normal_smoothing_iterations), bool(sph_normals), int(threads),
        int(memory_budget), bool(skip_invalid), bool(keep_raw_mesh))
    mesh = _mesh(result)
    mesh.stats = result["stats"]
    mesh.weights_normalization = result["weights_normalization"]
    if result["raw"] is not None:
        mesh.raw = _mesh(result["raw"])
    return mesh


def write_mesh(mesh: Mesh, path) -> None:
    """Writes .ply (binary, normals and attributes), .obj or .vtk, chosen by the extension."""
    attributes = {k: _attribute_array(v) for k, v in mesh.attributes.items()}
    normals = None if mesh.normals is None else np.ascontiguousarray(mesh.normals, dtype=np.float32)
    _core.write_mesh(str(path), np.ascontiguousarray(mesh.vertices, dtype=np.float32),
                     np.ascontiguousarray(mesh.triangles, dtype=np.int32), normals, attributes)


def read_mesh(path) -> Mesh:
    return _mesh(_core.read_mesh(str(path)))


def check_mesh(mesh: Mesh) -> dict:
    """Closed, manifold (edges and vertex fans), oriented, degenerate triangles: a dict of counts and flags."""
    return _core.check_mesh(np.ascontiguousarray(mesh.vertices, dtype=np.float32),
                            np.ascontiguousarray(mesh.triangles, dtype=np.int32))


def assess_quality(mesh: Mesh, threads: int = 0) -> dict:
    """Quality report: check, volume, components, bumpiness, normal angles, valences, barnacle counts."""
    return _core.assess_quality(np.ascontiguousarray(mesh.vertices, dtype=np.float32),
                                np.ascontiguousarray(mesh.triangles, dtype=np.int32), int(threads))
