// Stray blobs (post/stray_filter.h) and the particle clusters they are counted by (sph/clusters.h).
#include <catch2/catch.hpp>

#include "post/stray_filter.h"
#include "mesh/components.h"
#include "sph/clusters.h"
#include "surface/reconstruction.h"

using namespace meniscus;

namespace {

// A 6 x 6 x 6 block of particles at spacing 2 r, plus far-apart droplets of 1, 3 and 10 particles.
std::vector<float> block_and_droplets(double r) {
    std::vector<float> p;
    const float s = static_cast<float>(2 * r);
    for (int z = 0; z < 6; ++z)
        for (int y = 0; y < 6; ++y)
            for (int x = 0; x < 6; ++x) p.insert(p.end(), {x * s, y * s, z * s});
    const float far = static_cast<float>(60 * r);
    auto droplet = [&](int count, float offset) {
        for (int i = 0; i < count; ++i) p.insert(p.end(), {offset + (i % 3) * s, far + ((i / 3) % 3) * s, (i / 9) * s});
    };
    droplet(1, 0.0f);
    droplet(3, far);
    droplet(10, 2 * far);
    return p;
}

SurfaceReconstruction reconstruct(const std::vector<float>& p, double r) {
    ReconstructionParams params;
    params.particle_radius = r;
    params.cube_size = 0.75;
    return reconstruct_surface(PositionsView(p.data(), p.size() / 3), params, ExecutionOptions{});
}

int32_t components(const TriMesh& mesh) {
    int32_t count = 0;
    component_labels(mesh, &count);
    return count;
}

}  // namespace

TEST_CASE("particles within the kernel support form one cluster", "[strays]") {
    const double r = 0.025;
    SurfaceReconstruction s = reconstruct(block_and_droplets(r), r);
    const ParticleClusters clusters = cluster_particles(s.grid, s.params.compact_support());
    std::vector<int32_t> sizes = clusters.sizes;
    std::sort(sizes.begin(), sizes.end());
    REQUIRE(sizes == std::vector<int32_t>{1, 3, 10, 216});
}

TEST_CASE("pieces of fewer particles than the minimum are removed and counted", "[strays]") {
    const double r = 0.025;
    SurfaceReconstruction s = reconstruct(block_and_droplets(r), r);
    REQUIRE(components(s.mesh) == 4);
    TriMesh mesh = s.mesh;
    const StrayRemoval removed = remove_stray_components(mesh, s, 5, 0.0, 2);
    REQUIRE(removed.components == 2);
    REQUIRE(removed.particles == 4);  // the 1- and 3-particle droplets
    REQUIRE(removed.volume > 0.0);
    REQUIRE(components(mesh) == 2);
    for (int32_t index : mesh.triangles) REQUIRE(static_cast<std::size_t>(index) < mesh.num_vertices());

    // Off: nothing changes. By volume: the single particle's blob is below 2 particle volumes, the others are not.
    TriMesh unchanged = s.mesh;
    REQUIRE(remove_stray_components(unchanged, s, 0, 0.0, 1).components == 0);
    REQUIRE(unchanged.triangles == s.mesh.triangles);
    TriMesh by_volume = s.mesh;
    REQUIRE(remove_stray_components(by_volume, s, 0, 2.0, 1).components == 1);
    REQUIRE(components(by_volume) == 3);
}
