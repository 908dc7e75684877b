// Mesh post-processing of the paper (Sec. 3.3-3.4) and the quality measures used to check it. Every function
// works in place on a TriMesh (closed, 2-manifold, oriented input expected), keeps `normals` and per-vertex
// `attributes` consistent when it removes vertices, and gives the same result for any thread count.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "mesh/mesh.h"

namespace meniscus {

struct MeshAdjacency;  // mesh_adjacency.h: built once when the topology stops changing, shared by later stages

// ---- topology -------------------------------------------------------------------------------------------------
struct MeshCheck {
    std::size_t boundary_edges = 0;          // edges with one incident triangle
    std::size_t non_manifold_edges = 0;      // edges with more than two incident triangles
    std::size_t non_manifold_vertices = 0;   // vertices whose triangle fan is not a single disk
    std::size_t inconsistent_edges = 0;      // edges traversed in the same direction by both triangles
    std::size_t degenerate_triangles = 0;    // repeated vertex index or zero area
    std::size_t non_finite_vertices = 0;     // NaN or Inf coordinate
    std::size_t unreferenced_vertices = 0;
    bool closed() const { return boundary_edges == 0; }
    bool manifold() const { return non_manifold_edges == 0 && non_manifold_vertices == 0; }
    bool oriented() const { return inconsistent_edges == 0; }
    bool ok() const { return closed() && manifold() && oriented() && degenerate_triangles == 0 && non_finite_vertices == 0; }
    std::string summary() const;  // "closed, manifold, oriented" or what is wrong with counts
};
MeshCheck check_mesh(const TriMesh& mesh);
// Exactly zero area (cross product of the edges, in double, is the zero vector): the check's criterion.
bool triangle_has_zero_area(const float* vertices, const int32_t* triangle);

// ---- decimation (Sec. 3.3) ------------------------------------------------------------------------------------
// Removes the "single vertex" and "double vertex" marching-cubes configurations with legal half-edge collapses
// (link condition) of their one-rings into the centre vertices. Returns the number of configurations removed.
// With final_adjacency, also hands over the adjacency of the resulting mesh when its last detection pass already
// built it (left empty otherwise), so the caller need not build it again.
struct MeshAdjacency;
std::size_t decimate_barnacles(TriMesh& mesh, int threads, MeshAdjacency* final_adjacency = nullptr);
// Counts the single-/double-vertex configurations present (for reports and tests).
std::size_t count_single_vertex_configurations(const TriMesh& mesh);
std::size_t count_double_vertex_configurations(const TriMesh& mesh);

// "Mesh cleanup": collapses one-ring neighbours that share the same nearest grid point (lattice of spacing
// cube_edge anchored at the origin) into one vertex at their average position. snap_distance < 0: all
// vertices take part; otherwise only those within snap_distance * cube_edge of their grid point.
// Returns the number of vertices removed.
std::size_t mesh_cleanup(TriMesh& mesh, double cube_edge, double snap_distance, int threads);

// ---- smoothing (Eq. 3-5) --------------------------------------------------------------------------------------
// Weighted explicit uniform-Laplacian smoothing with a Jacobi update: x_i += beta * w_i * (mean(x_j) - x_i).
// weights: one per vertex in [0, 1]; empty means 1 everywhere (plain uniform smoothing).
void laplacian_smooth(TriMesh& mesh, const std::vector<float>& weights, int iterations, double beta, int threads);
void laplacian_smooth(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& weights, int iterations, double beta,
                      int threads);

// ---- normals (Sec. 3.4) ---------------------------------------------------------------------------------------
void compute_area_weighted_normals(TriMesh& mesh, int threads);   // fills mesh.normals
void smooth_normals(TriMesh& mesh, int iterations, int threads);  // Eq. 12 on mesh.normals
void compute_area_weighted_normals(TriMesh& mesh, const MeshAdjacency& adjacency, int threads);
void smooth_normals(TriMesh& mesh, const MeshAdjacency& adjacency, int iterations, int threads);

// ---- quality report -------------------------------------------------------------------------------------------
struct ComponentQuality {
    std::size_t triangles = 0;
    double volume = 0.0;  // signed: positive for fluid bodies and droplets, negative for enclosed bubbles
};
struct MeshQuality {
    MeshCheck check;
    std::size_t vertices = 0, triangles = 0;
    double volume = 0.0;                          // enclosed, signed (divergence theorem)
    double area = 0.0;
    std::vector<ComponentQuality> components;     // sorted by volume, largest first
    double bumpiness = 0.0;                       // mean distance to own Taubin low-pass (see quality.cpp)
    double mean_normal_angle_deg = 0.0;           // mean angle between adjacent face normals
    std::vector<std::size_t> valence_histogram;   // index = valence
    std::size_t single_vertex_configurations = 0;
    std::size_t double_vertex_configurations = 0;
    double mean_edge_length = 0.0;
    // Bumpiness at a physical scale (analysis/scale_metrics.h), when assess_quality is given a length L (2 r):
    double scale_length = 0.0;                    // L
    int hfl_passes = 0;                           // round(1.36 (L / e)^2), e the raw mesh's mean edge length
    double hfl = 0.0;                             // mean distance to own Taubin low-pass with hfl_passes pairs
    double heat_bumpiness = 0.0;                  // mean distance to own heat low-pass of time L^2 / 4
};
// scale_length > 0 adds the measures at that scale; raw_mean_edge is the raw mesh's mean edge length, which sets the
// hfL pass count for the raw and the smoothed mesh alike (0: this mesh's own).
MeshQuality assess_quality(const TriMesh& mesh, int threads = 0, double scale_length = 0.0, double raw_mean_edge = 0.0);

}  // namespace meniscus
