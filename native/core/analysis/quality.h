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
};

MeshQuality assess_quality(const TriMesh& mesh, int threads = 0);

}  // namespace meniscus
