// A coarse copy of a surface mesh for filters of long reach (issue 12's smoothing at c = 0.25 runs ~250 explicit
// iterations' worth on millions of vertices). Vertices are grouped into aggregates: the pieces of the surface inside
// one cell of a spatial grid that the mesh's own edges connect, so two sheets or a droplet beside a pool that pass
// through the same cell stay apart. Aggregates are coupled where mesh edges cross between them, weighted by how many
// do (a long shared border couples more than a corner). A field smooth at several cells' scale, restricted to the
// aggregates (weighted means), filtered there and prolonged back (post/heat_smoothing.cpp: a distance-weighted mean
// over the vertex's aggregate and the coupled ones, then a short fine blend) keeps what a filter on the mesh would
// give, at a fraction of the cost.
//
// Deterministic: aggregates are numbered by their smallest vertex, rows and sums run in index order.
#pragma once
#include <cstdint>
#include <vector>

#include "base/uninitialized_vector.h"
#include "mesh/adjacency.h"
#include "mesh/mesh.h"

namespace meniscus {

struct SurfaceAggregates {
    UninitializedVector<int32_t> of_vertex;  // aggregate of each vertex
    CsrList members;                 // vertices of each aggregate, ascending
    CsrList neighbours;              // aggregates sharing a mesh edge with each aggregate, ascending
    std::vector<float> coupling;     // per neighbours item: the number of mesh edges between the two

    std::size_t size() const { return members.rows(); }
};

// Groups the vertices by cells of edge `cell` (scene units). Returns no aggregates at all when the mesh spans more than
// 2^21 cells along an axis (the cell keys' range); callers then filter on the mesh.
SurfaceAggregates aggregate_surface(const TriMesh& mesh, const MeshAdjacency& adjacency, double cell, int threads);

// Weighted mean per aggregate of `dims` (1 to 3) values per vertex, one weight per vertex (where an aggregate's weights
// add up to 0: the plain mean).
std::vector<double> restrict_to_aggregates(const SurfaceAggregates& aggregates, const std::vector<float>& vertex_weights,
                                           const float* values, int dims, int threads);

// Root-mean-square distance between coupled aggregates' points (3 per aggregate), weighted by the coupling: the
// coarse graph's edge length, as rms_edge_length is the mesh's.
double rms_coupled_distance(const SurfaceAggregates& aggregates, const std::vector<double>& points, int threads);

// x <- sum_k c_k T_k(Y) x on the aggregate graph, Y = I + w (coupling-weighted mean - I) per aggregate, `dims`
// values per aggregate; weights (one per aggregate in [0, 1]) may be empty (1). With heat_coefficients (post/
// heat_smoothing.h) the mesh's heat_filter on the coarse graph. Aggregates without coupled ones or of weight 0 are
// Y's fixed points (Y x = x there). Returns the number of operator applications.
int aggregate_chebyshev(std::vector<double>& x, int dims, const SurfaceAggregates& aggregates, const std::vector<double>& weights,
                        const std::vector<double>& coefficients, int threads);

}  // namespace meniscus
