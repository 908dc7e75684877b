// The whole per-frame pipeline, one function of particles and parameters:
// particles -> reconstruction (neighbourhood, densities and neighbour counts, level set, marching cubes)
// -> mesh cleanup or barnacle decimation -> feature weights -> weighted Laplacian smoothing -> normals
// (area-weighted, smoothed; or SPH) -> particle attributes interpolated onto the final vertices.
#pragma once
#include <string>
#include <vector>

#include "mesh/mesh.h"
#include "parameters.h"
#include "sph/particles.h"
#include "base/stats.h"

namespace meniscus {

// A per-particle attribute given by the caller, read in place: values[i * components + k].
struct AttributeInput {
    std::string name;
    const float* values = nullptr;
    int components = 1;
    bool integral = false;  // whole numbers (ids, labels): the nearest particle's value, not an average
};

struct PipelineOptions : Parameters {
    bool keep_raw_mesh = false;  // also return the mesh as marching cubes made it
};

struct PipelineResult {
    TriMesh mesh;
    TriMesh raw_mesh;                   // filled when keep_raw_mesh
    PipelineStats stats;
    double weights_normalization = 0;   // N_HS used (0 when no weights were computed)
};

PipelineResult run_pipeline(const PositionsView& positions, const std::vector<AttributeInput>& attributes, const PipelineOptions& options);

}  // namespace meniscus
