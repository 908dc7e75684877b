#include "post/stray_filter.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "base/numbers.h"
#include "mesh/components.h"
#include "sph/clusters.h"

namespace meniscus {

namespace {

// The cluster of the particle nearest to a point (within the kernel support), or -1 when there is none.
int32_t cluster_near(const SurfaceReconstruction& r, const ParticleClusters& clusters, const float* point) {
    float nearest = INFINITY;
    int32_t cluster = -1;
    r.grid.for_each_neighbor(point, static_cast<float>(r.params.compact_support()), [&](std::size_t j, float d2) {
        if (d2 < nearest) {
            nearest = d2;
            cluster = clusters.of_particle[j];
        }
    });
    return cluster;
}

// Keeps the triangles of the kept components and the vertices they use, renumbered in their old order. (The mesh
// has no normals or attributes yet at this stage.)
void keep_components(TriMesh& mesh, const std::vector<int32_t>& labels, const std::vector<uint8_t>& removed) {
    std::vector<int32_t> triangles;
    triangles.reserve(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t)
        if (!removed[labels[mesh.triangles[3 * t]]]) triangles.insert(triangles.end(), &mesh.triangles[3 * t], &mesh.triangles[3 * t] + 3);
    std::vector<int32_t> renumbered(mesh.num_vertices(), -1);
    std::vector<float> vertices;
    int32_t next = 0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
        if (!removed[labels[v]]) {
            renumbered[v] = next++;
            vertices.insert(vertices.end(), &mesh.vertices[3 * v], &mesh.vertices[3 * v] + 3);
        }
    for (int32_t& index : triangles) index = renumbered[index];
    mesh.vertices.swap(vertices);
    mesh.triangles.swap(triangles);
}

}  // namespace

StrayRemoval remove_stray_components(TriMesh& mesh, const SurfaceReconstruction& r, int min_particles, double min_volume,
                                     int threads) {
    StrayRemoval result;
    if ((min_particles <= 0 && min_volume <= 0.0) || mesh.num_vertices() == 0) return result;
    int32_t count = 0;
    const std::vector<int32_t> labels = component_labels(mesh, &count);
    const std::vector<double> volumes = component_volumes(mesh, labels, count, threads);
    const double radius = r.params.particle_radius;
    const double particle_volume = 4.0 / 3.0 * kPi * radius * radius * radius;

    // Each component's cluster: that of the particle nearest to its first vertex.
    std::vector<int32_t> cluster(static_cast<std::size_t>(count), -2);
    ParticleClusters clusters;
    if (min_particles > 0) {
        clusters = cluster_particles(r.grid, r.params.compact_support());
        for (std::size_t v = 0; v < mesh.num_vertices(); ++v)
            if (cluster[labels[v]] == -2) cluster[labels[v]] = cluster_near(r, clusters, &mesh.vertices[3 * v]);
    }
    std::vector<uint8_t> removed(static_cast<std::size_t>(count), 0), cluster_counted(clusters.sizes.size(), 0);
    for (int32_t c = 0; c < count; ++c) {
        if (volumes[c] <= 0.0) continue;  // an enclosed bubble
        const int32_t particles = cluster[c] >= 0 ? clusters.sizes[cluster[c]] : 0;
        const bool few = min_particles > 0 && particles < min_particles;
        const bool small = min_volume > 0.0 && volumes[c] < min_volume * particle_volume;
        if (!few && !small) continue;
        removed[c] = 1;
        ++result.components;
        result.volume += volumes[c];
        if (cluster[c] >= 0 && !cluster_counted[cluster[c]]) {  // a cluster may make several pieces: counted once
            cluster_counted[cluster[c]] = 1;
            result.particles += static_cast<std::size_t>(particles);
        }
    }
    if (result.components) keep_components(mesh, labels, removed);
    return result;
}

}  // namespace meniscus
