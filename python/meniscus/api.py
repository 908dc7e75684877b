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

import inspect

import numpy as np

from . import _core
from . import parameters as _parameters

__all__ = ["FormatError", "Mesh", "Particles", "__version__", "assess_quality", "check_mesh", "read_mesh",
           "read_particles", "reconstruct", "write_mesh"]

FormatError = _core.FormatError
__version__ = _core.__version__


@dataclass
class Particles:
    positions: np.ndarray                      # (N, 3) float32
    # (N,) or (N, k): float32, or int32 for whole-number fields of the file (ids, labels)
    attributes: Dict[str, np.ndarray] = field(default_factory=dict)
    # The grid solver's domain from its cache (Mantaflow), as a dict mirroring FluidDomain (origin, axes, resolution,
    # closed_borders, gravity, band_width_cells, obstacles); None for other files. reconstruct() takes it.
    fluid_domain: Optional[dict] = None

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
    quads: Optional[np.ndarray] = None         # (Q, 4) int32 with generate_quads: merged triangle pairs, same winding

    def write(self, path: str) -> None:
        write_mesh(self, path)

    def all_triangles(self) -> np.ndarray:
        """The triangles with every quad split back into two (for tools that take triangles only)."""
        if self.quads is None or len(self.quads) == 0:
            return np.ascontiguousarray(self.triangles, dtype=np.int32)
        quads = np.asarray(self.quads, dtype=np.int32)
        return np.concatenate([np.asarray(self.triangles, dtype=np.int32).reshape(-1, 3),
                               quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def _attribute_array(values) -> np.ndarray:
    """Integer and bool arrays (ids, labels, flags) go to the core as they are, which carries them as whole numbers
    (from the nearest particle, never averaged); anything else as float32 (copied only when it is not already)."""
    values = np.asarray(values)
    if values.dtype.kind in "iub":
        return np.ascontiguousarray(values)
    return np.ascontiguousarray(values, dtype=np.float32)


def _mesh(result: dict) -> Mesh:
    quads = result.get("quads")
    return Mesh(result["vertices"], result["triangles"], result["normals"], result["attributes"],
                quads=quads if quads is not None and len(quads) else None)


def read_particles(path) -> Particles:
    """Reads a particle file (legacy VTK, BGEO); raises FormatError naming the file and the fault."""
    data = _core.read_particles(str(path))
    return Particles(data["positions"], data["attributes"], data.get("fluid_domain"))


def reconstruct(positions, particle_radius, *, attributes: Optional[Dict[str, np.ndarray]] = None,
                keep_raw_mesh: bool = False, fluid_domain: Optional[dict] = None, **parameters) -> Mesh:
    # The signature and the parameters' documentation are filled in from the schema below (see parameters.py).
    unknown = sorted(set(parameters) - set(_parameters.BY_NAME))
    if unknown:
        raise TypeError(f"reconstruct() got unknown parameter(s) {', '.join(map(repr, unknown))}; "
                        f"the parameters are: {', '.join(_parameters.BY_NAME)}")
    converted = {}
    for name, values in (attributes or {}).items():
        converted[str(name)] = _attribute_array(values)
    result = _core.reconstruct(positions, converted, {"particle_radius": particle_radius, **parameters},
                               bool(keep_raw_mesh), fluid_domain)
    mesh = _mesh(result)
    mesh.stats = result["stats"]
    mesh.weights_normalization = result["weights_normalization"]
    if result["raw"] is not None:
        mesh.raw = _mesh(result["raw"])
    return mesh


def _document_reconstruct():
    """reconstruct()'s signature and docstring from the schema: help(), IDEs and inspect show every parameter."""
    keyword = inspect.Parameter.KEYWORD_ONLY
    signature = [inspect.Parameter("positions", inspect.Parameter.POSITIONAL_OR_KEYWORD),
                 inspect.Parameter("particle_radius", inspect.Parameter.POSITIONAL_OR_KEYWORD),
                 inspect.Parameter("attributes", keyword, default=None),
                 inspect.Parameter("keep_raw_mesh", keyword, default=False),
                 inspect.Parameter("fluid_domain", keyword, default=None)]
    lines = ["Reconstructs the fluid surface of (N, 3) float32/float64 C-contiguous positions (read without a copy).",
             "",
             "attributes: per-particle arrays to carry onto the surface (float: interpolated; integer: from the",
             "    nearest particle). keep_raw_mesh: also return the marching-cubes mesh as mesh.raw.",
             "fluid_domain: the grid solver's domain the particles come from (Particles.fluid_domain, or a dict with",
             "    origin, axes, resolution, closed_borders, gravity, band_width_cells, obstacles, and Mantaflow's Mesh",
             "    settings mesh_upres, mesh_particle_radius, mesh_smoothen_pos/neg, mesh_concave_lower/upper): Mantaflow's",
             "    own surface (fluid_surface) or the interior fill (fill_interior) makes solid water from a narrow band",
             "    of particles with it. Its object_to_world (the domain object's matrix the frame was simulated with,",
             "    column-major) is not used by either.",
             "Raises ValueError naming a bad argument, MemoryError (with the estimate) beyond the memory budget.",
             "",
             "Parameters (the same as the command line's flags and the Blender add-on's properties):"]
    for parameter in _parameters.PARAMETERS:
        if parameter.name != "particle_radius":
            signature.append(inspect.Parameter(parameter.name, keyword, default=parameter.python_default))
        lines.append(f"  {parameter.name}: {parameter.describe()}")
    reconstruct.__signature__ = inspect.Signature(signature)
    reconstruct.__doc__ = "\n".join(lines)


_document_reconstruct()


def write_mesh(mesh: Mesh, path) -> None:
    """Writes .ply (binary, normals and attributes), .obj or .vtk, chosen by the extension."""
    attributes = {k: _attribute_array(v) for k, v in mesh.attributes.items()}
    normals = None if mesh.normals is None else np.ascontiguousarray(mesh.normals, dtype=np.float32)
    quads = None if mesh.quads is None else np.ascontiguousarray(mesh.quads, dtype=np.int32)
    _core.write_mesh(str(path), np.ascontiguousarray(mesh.vertices, dtype=np.float32),
                     np.ascontiguousarray(mesh.triangles, dtype=np.int32), normals, attributes, quads)


def read_mesh(path) -> Mesh:
    return _mesh(_core.read_mesh(str(path)))


def blender_mesh_arrays(triangles, quads=None, vertex_count: int = 0, threads: int = 0) -> dict:
    """The faces of a mesh in the layout Blender's Mesh stores, computed by the core (Python's lock released):
    corner_vertices (C,) the triangles' corners then the quads', face_offsets (F,) each face's first corner, edges
    (E, 2) as (low, high) vertex pairs in ascending order and corner_edges (C,) each corner's edge to the next corner
    of its face (int32; edges and corner_edges None when a face repeats a vertex)."""
    quads = None if quads is None or len(quads) == 0 else np.ascontiguousarray(quads, dtype=np.int32).reshape(-1, 4)
    return _core.blender_mesh_arrays(np.ascontiguousarray(triangles, dtype=np.int32).reshape(-1, 3), quads,
                                     int(vertex_count), int(threads))


def check_mesh(mesh: Mesh) -> dict:
    """Closed, manifold (edges and vertex fans), oriented, degenerate triangles: a dict of counts and flags."""
    return _core.check_mesh(np.ascontiguousarray(mesh.vertices, dtype=np.float32), mesh.all_triangles())


def assess_quality(mesh: Mesh, threads: int = 0, particle_radius: Optional[float] = None, raw: Optional[Mesh] = None) -> dict:
    """Quality report: check, volume, components, bumpiness, normal angles, valences, barnacle counts, mean edge length.

    With particle_radius, also the bumpiness at L = 2 r: "hfl" (mean distance to the mesh's own Taubin low-pass with
    round(1.36 (L / e)^2) passes, e the raw mesh's mean edge length when raw is given, else this mesh's own) and
    "heat_bumpiness" (the same against a heat low-pass of time L^2 / 4, which does not depend on the cube size). With
    raw as well: "raw" (its report) and the ratios "volume_ratio", "hfl_ratio", "heat_bumpiness_ratio".
    """
    def report(m, raw_edge=0.0):
        return _core.assess_quality(np.ascontiguousarray(m.vertices, dtype=np.float32), m.all_triangles(), int(threads),
                                    2.0 * float(particle_radius) if particle_radius else 0.0, float(raw_edge))
    if raw is None:
        return report(mesh)
    raw_report = report(raw)
    out = report(mesh, raw_report["mean_edge_length"])
    out["raw"] = raw_report
    out["volume_ratio"] = out["volume"] / raw_report["volume"] if raw_report["volume"] else 0.0
    out["bumpiness_ratio"] = out["bumpiness"] / raw_report["bumpiness"] if raw_report["bumpiness"] else 0.0
    if particle_radius:
        out["hfl_ratio"] = out["hfl"] / raw_report["hfl"] if raw_report["hfl"] else 0.0
        out["heat_bumpiness_ratio"] = out["heat_bumpiness"] / raw_report["heat_bumpiness"] if raw_report["heat_bumpiness"] else 0.0
    return out
