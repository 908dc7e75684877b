// The whole per-frame pipeline, one function of particles and parameters (pipeline.cpp lists the stages):
// particles -> reconstruction (neighbourhood, densities and neighbour counts, level set, marching cubes; surface/)
// -> mesh cleanup and/or barnacle decimation -> feature weights -> weighted Laplacian smoothing -> volume
// restoration -> normals (area-weighted, smoothed; or SPH) -> particle attributes carried onto the final vertices
// (post/, sph/).
#pragma once
#include <vector>

#include "base/attributes.h"
#include "base/stats.h"
#include "mesh/mesh.h"
#include "parameters.h"
#include "sph/particles.h"

namespace meniscus {

struct PipelineOptions : Parameters {
    bool keep_raw_mesh = false;  // also return the mesh as marching cubes made it
    // The grid solver's domain the particles come from (ParticleData::fluid_domain), for the narrow-band fill.
    const FluidDomain* fluid_domain = nullptr;
};

struct PipelineResult {
    TriMesh mesh;
    TriMesh raw_mesh;                   // filled when keep_raw_mesh
    PipelineStats stats;
    double weights_normalization = 0;   // N_HS used (0 when no weights were computed)
};

PipelineResult run_pipeline(const PositionsView& positions, const std::vector<AttributeInput>& attributes, const PipelineOptions& options);

}  // namespace meniscus
