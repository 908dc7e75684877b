// Surface reconstruction (paper Sec. 3.1): SPH densities, the colour field of Eq. 1 sampled on a sparse grid
// anchored to the global lattice of the cube size, and marching cubes with Eq. 2.
//
// Data flow: particles -> ParticleGrid (cells of edge H) -> per-particle density (and, in the same neighbour
// loop, the hat-weighted neighbour count of Eq. 10-11 used later by the feature weights) -> active bricks of
// 32^3 cubes near particles -> per brick, in parallel: colour field, edge vertices, triangles -> stitching of the
// bricks by edge ownership. Each brick is independent and the stitching visits bricks in key order, so the mesh
// is the same, bit for bit, for any thread count.
#pragma once
#include <functional>
#include <vector>

#include "mesh/mesh.h"
#include "sph/neighborhood.h"
#include "parameters.h"
#include "sph/particles.h"
#include "base/stats.h"

namespace meniscus {

struct SurfaceReconstruction {
    ReconstructionParams params;
    ParticleGrid grid;                    // sorted particles, reused by weights and interpolation (Sec. 4)
    std::vector<float> volumes;           // m_j / rho_j per sorted particle
    std::vector<float> neighbor_counts;   // hat-weighted neighbour count (Eq. 11) per sorted particle
    TriMesh mesh;                         // raw marching-cubes mesh (no normals yet)
};

// Validates the parameters (InputError naming the bad one), refuses NaN/Inf positions unless
// execution.skip_invalid, and refuses grids beyond the memory budget (ResourceError with the estimate).
SurfaceReconstruction reconstruct_surface(const PositionsView& positions, const ReconstructionParams& params,
                                          const ExecutionOptions& execution, PipelineStats* stats = nullptr);


// Marching cubes alone, on a field given as a function (for tests and analytic surfaces): the same table, bricks
// and stitching as the reconstruction, over the lattice of cube_edge covering [lower, upper]. The field must be
// below the threshold on and outside that box for the mesh to be closed.
TriMesh marching_cubes_on_function(const std::function<float(double, double, double)>& field, const double lower[3],
                                   const double upper[3], double cube_edge, double threshold, int threads);

// Shepard-corrected SPH interpolation (Eq. 7) of per-particle values (in the caller's original particle order,
// `components` floats each) at the given points: sum_j V_j W_j A_j / sum_j V_j W_j; points without any particle
// within the support get 0. out has points * components floats.
void interpolate_at_points(const SurfaceReconstruction& reconstruction, const float* particle_values, int components,
                           const std::vector<float>& points, std::vector<float>& out, int threads);

// Each point takes the values of its nearest particle within the support (the first in sorted order on a tie;
// 0 where there is none): the transfer for whole-number attributes (particle ids, phase or emitter labels, flags),
// whose averages would mean nothing.
void nearest_particle_at_points(const SurfaceReconstruction& reconstruction, const float* particle_values, int components,
                                const std::vector<float>& points, std::vector<float>& out, int threads);

// The same for values given per sorted particle (as volumes and neighbor_counts are).
void interpolate_sorted_at_points(const SurfaceReconstruction& reconstruction, const float* sorted_values, int components,
                                  const std::vector<float>& points, std::vector<float>& out, int threads);

// Outward unit normals from the colour-field gradient (SPH normals) at the given points.
std::vector<float> colour_field_normals(const SurfaceReconstruction& reconstruction, const std::vector<float>& points, int threads);

}  // namespace meniscus
