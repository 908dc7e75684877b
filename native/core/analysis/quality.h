// Quality report of a surface mesh: the topology check, enclosed volume and area, the connected components with
// their volumes, and the smoothness measures used to compare post-processing settings (bumpiness, normal angles,
// valences, barnacle configurations). The same numbers, bit for bit, for any thread count.
#pragma once
#include <cstddef>
#include <vector>

#include "mesh/mesh.h"
#include "mesh/topology.h"

namespace meniscus {

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
