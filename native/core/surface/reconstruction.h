// Surface reconstruction (paper Sec. 3.1): particles -> particle grid (cells of edge H, sph/neighborhood.h) ->
// densities and hat-weighted neighbour counts in one neighbour pass (sph/density.h) -> the colour field of Eq. 1 on
// the bricks near the particles (level_set.h) -> marching cubes with Eq. 2 per brick, stitched (bricks.h). Each
// brick is independent and the stitching visits bricks in key order, so the mesh is the same, bit for bit, for any
// thread count. The grid and the densities stay with the result: the feature weights, the SPH normals and the
// attribute transfer sample the same particles (Sec. 4).
#pragma once
#include <cstdint>
#include <vector>

#include "base/stats.h"
#include "mesh/mesh.h"
#include "parameters.h"
#include "sph/density.h"
#include "sph/interpolation.h"
#include "sph/neighborhood.h"
#include "sph/particles.h"

namespace meniscus {

struct SurfaceReconstruction {
    ReconstructionParams params;
    ParticleGrid grid;              // sorted particles
    ParticleDensities densities;    // per sorted particle: volume and hat-weighted neighbour count
    TriMesh mesh;                   // raw marching-cubes mesh (no normals)

    // The particles as an SPH field, for sums at the mesh's vertices (valid while this reconstruction lives).
    SphField sph_field() const { return {grid, densities.volumes, CubicSplineKernel(params.compact_support())}; }
};

// Validates the parameters (InputError naming the bad one), refuses NaN/Inf positions unless
// execution.skip_invalid, and refuses meshes beyond the memory budget (ResourceError with the estimate). Adds the
// stages' seconds ("neighborhood", "density", "level set and marching cubes") and counts to stats when given.
// With a container: particles outside its particle box are left out (counted as "particles_outside_box"), and with a
// capped mesh box the surface is closed against the box's walls (bricks.h, MeshBox).
// Non-finite positions: InputError with a count, or dropped (a warning in stats) when execution.skip_invalid.
// Returns the particles to keep (empty: all).
std::vector<uint8_t> finite_particles(const PositionsView& positions, const ExecutionOptions& execution, PipelineStats* stats);

SurfaceReconstruction reconstruct_surface(const PositionsView& positions, const ReconstructionParams& params,
                                          const ExecutionOptions& execution, PipelineStats* stats = nullptr,
                                          const ContainerParams* container = nullptr);

}  // namespace meniscus
