// The container (issue 13, part 1; post/container.h, surface/bricks.h MeshBox): a block of fluid cut by a box
// within the particles' reach. Capped: every vertex in the box, the faces on the walls flat, closed and manifold,
// the volume of the raw mesh clipped to the box; open cut and clamping as splashsurf; the particle box's count;
// the same bits for any thread count.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "mesh/topology.h"
#include "mesh_builders.h"
#include "pipeline.h"

using namespace meniscus;
using namespace meniscus::test;

namespace {

constexpr double kRadius = 0.025;

// Particles on a lattice of spacing 2r filling [0, 0.6] x [0, 0.6] x [0, 0.4].
std::vector<float> fluid_block() {
    std::vector<float> p;
    for (int z = 0; z < 8; ++z)
        for (int y = 0; y < 12; ++y)
            for (int x = 0; x < 12; ++x)
                for (double c : {kRadius * (1 + 2 * x), kRadius * (1 + 2 * y), kRadius * (1 + 2 * z)}) p.push_back(static_cast<float>(c));
    return p;
}

// The box cuts the block on its four sides and its floor, off the marching-cubes lattice (cube edge 0.0125); the
// top is above the fluid, which stays a free surface.
const Vector3 kLower{0.1031, 0.0977, 0.0712}, kUpper{0.4969, 0.5023, 1.0};

PipelineOptions container_options(int threads) {
    PipelineOptions options;
    options.reconstruction = reconstruction_params(kRadius, 0.5);
    options.execution.threads = threads;
    options.container.mesh_aabb_min = kLower;
    options.container.mesh_aabb_max = kUpper;
    return options;
}

PipelineResult run(const std::vector<float>& particles, const PipelineOptions& options) {
    return run_pipeline(PositionsView(particles.data(), particles.size() / 3), {}, options);
}

bool inside_box(const float* p) {
    for (int k = 0; k < 3; ++k)
        if (p[k] < static_cast<float>(kLower[k]) || p[k] > static_cast<float>(kUpper[k])) return false;
    return true;
}

// Volume of a closed mesh's intersection with the box: along vertical rays on a fine grid of columns, the inside
// intervals (crossings in pairs) clipped to the box's heights.
double clipped_volume(const TriMesh& mesh, int columns) {
    const double dx = (kUpper[0] - kLower[0]) / columns, dy = (kUpper[1] - kLower[1]) / columns;
    std::vector<std::vector<int32_t>> bins(static_cast<std::size_t>(columns * columns));
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 2; ++k) {
                const double v = mesh.vertices[3 * mesh.triangles[3 * t + c] + k];
                lo[k] = std::min(lo[k], v), hi[k] = std::max(hi[k], v);
            }
        const int i0 = std::max(0, int(std::floor((lo[0] - kLower[0]) / dx))), i1 = std::min(columns - 1, int(std::floor((hi[0] - kLower[0]) / dx)));
        const int j0 = std::max(0, int(std::floor((lo[1] - kLower[1]) / dy))), j1 = std::min(columns - 1, int(std::floor((hi[1] - kLower[1]) / dy)));
        for (int j = j0; j <= j1; ++j)
            for (int i = i0; i <= i1; ++i) bins[static_cast<std::size_t>(j * columns + i)].push_back(static_cast<int32_t>(t));
    }
    double volume = 0.0;
    std::vector<double> hits;
    for (int j = 0; j < columns; ++j)
        for (int i = 0; i < columns; ++i) {
            // Slightly off the column centre, so that no ray runs through a lattice-aligned edge.
            const double x = kLower[0] + (i + 0.5 + 1e-4) * dx, y = kLower[1] + (j + 0.5 + 2e-4) * dy;
            hits.clear();
            for (int32_t t : bins[static_cast<std::size_t>(j * columns + i)]) {
                const V3 a = vertex_of(mesh, mesh.triangles[3 * t]), b = vertex_of(mesh, mesh.triangles[3 * t + 1]),
                         c = vertex_of(mesh, mesh.triangles[3 * t + 2]);
                const double d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
                if (d == 0.0) continue;
                const double u = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / d;
                const double v = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / d;
                if (u < 0 || v < 0 || u + v > 1) continue;
                hits.push_back(a[2] + u * (b[2] - a[2]) + v * (c[2] - a[2]));
            }
            std::sort(hits.begin(), hits.end());
            REQUIRE(hits.size() % 2 == 0);
            for (std::size_t h = 0; h + 1 < hits.size(); h += 2)
                volume += std::max(0.0, std::min(hits[h + 1], kUpper[2]) - std::max(hits[h], kLower[2])) * dx * dy;
        }
    return volume;
}

// Area of the triangles lying on wall f (all three vertices within `tolerance` of its plane).
double area_on_wall(const TriMesh& mesh, int f, double tolerance) {
    const double plane = f % 2 ? kUpper[f / 2] : kLower[f / 2];
    double area = 0.0;
    for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
        bool on = true;
        for (int c = 0; c < 3; ++c) on = on && std::fabs(mesh.vertices[3 * mesh.triangles[3 * t + c] + f / 2] - plane) <= tolerance;
        if (on) area += 0.5 * length(triangle_cross(mesh.vertices.data(), &mesh.triangles[3 * t]));
    }
    return area;
}

}  // namespace

TEST_CASE("capped container: inside the box, flat on the walls, closed, the clipped raw volume", "[container]") {
    const std::vector<float> particles = fluid_block();
    PipelineOptions options = container_options(2);
    options.keep_raw_mesh = true;
    const PipelineResult capped = run(particles, options);
    const TriMesh& mesh = capped.mesh;
    REQUIRE(mesh.num_triangles() > 1000);

    const MeshCheck check = check_mesh(mesh);
    INFO(check.summary());
    CHECK(check.ok());
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) REQUIRE(inside_box(&mesh.vertices[3 * v]));

    // Faces on the walls: every triangle facing out through a wall (normal within 2 degrees of the wall's) with its
    // vertices near the wall (a quarter cube) lies on it within 1e-6 of the box size. (Near the contact line the free
    // surface may come close to a wall at a slant; those faces are not on it.) And the floor, which the fluid
    // covers, is covered by such faces up to the box's edges (no bevel where two walls meet).
    const double size = kUpper[0] - kLower[0];
    const double cube = options.reconstruction.cube_edge();
    double flatness = 0.0;
    std::size_t wall_faces = 0;
    for (int f = 0; f < 5; ++f) {
        const double plane = f % 2 ? kUpper[f / 2] : kLower[f / 2];
        for (std::size_t t = 0; t < mesh.num_triangles(); ++t) {
            double worst = 0.0;
            for (int c = 0; c < 3; ++c) worst = std::max(worst, std::fabs(mesh.vertices[3 * mesh.triangles[3 * t + c] + f / 2] - plane));
            const Vec3d n = triangle_cross(mesh.vertices.data(), &mesh.triangles[3 * t]);
            const double outward = (f % 2 ? 1.0 : -1.0) * (f / 2 == 0 ? n.x : f / 2 == 1 ? n.y : n.z);
            if (worst <= 0.25 * cube && outward >= std::cos(2.0 * 3.14159265358979 / 180.0) * length(n)) {
                flatness = std::max(flatness, worst);
                ++wall_faces;
            }
        }
    }
    INFO("largest distance of a wall face's vertex to its plane: " << flatness / size << " of the box size");
    CHECK(flatness <= 1e-6 * size);
    CHECK(wall_faces > 1000);
    const double floor_area = (kUpper[0] - kLower[0]) * (kUpper[1] - kLower[1]);
    const double floor_covered = area_on_wall(mesh, 4, 1e-6 * size);
    INFO("floor covered by flat faces: " << floor_covered / floor_area);
    CHECK(floor_covered == Approx(floor_area).epsilon(1e-5));
    for (int f = 0; f < 4; ++f) CHECK(area_on_wall(mesh, f, 1e-6 * size) > 0.8 * size * (0.4 - kLower[2]));

    // The free surface meets the side walls without sagging: each side wall's cap reaches as high as in the raw
    // mesh (within a twentieth of a cube), which is within a cube of the raw top surface.
    const auto highest = [](const TriMesh& m, int f) {
        float top = -1e30f;
        for (std::size_t v = 0; v < m.num_vertices(); ++v)
            if (f < 0 || m.vertices[3 * v + f / 2] == static_cast<float>(f % 2 ? kUpper[f / 2] : kLower[f / 2]))
                top = std::max(top, m.vertices[3 * v + 2]);
        return double(top);
    };
    for (int f = 0; f < 4; ++f) {
        INFO("wall " << f << ": cap up to " << highest(mesh, f) << ", raw " << highest(capped.raw_mesh, f) << ", raw top surface "
                     << highest(capped.raw_mesh, -1));
        CHECK(highest(mesh, f) >= highest(capped.raw_mesh, f) - 0.05 * cube);
        CHECK(highest(capped.raw_mesh, f) > highest(capped.raw_mesh, -1) - cube);
    }

    // Volume: the raw mesh of the same particles without a container, clipped to the box.
    PipelineOptions open = options;
    open.container = ContainerParams{};
    const PipelineResult uncut = run(particles, open);
    const double reference = clipped_volume(uncut.raw_mesh, 400);
    const double volume = signed_volume(mesh);
    INFO("volume " << volume << ", raw mesh clipped to the box " << reference << ", capped raw " << signed_volume(capped.raw_mesh));
    CHECK(volume == Approx(reference).epsilon(0.01));
    CHECK(signed_volume(capped.raw_mesh) == Approx(reference).epsilon(0.01));
}

TEST_CASE("capped container on lattice-aligned walls stays closed and inside", "[container]") {
    const std::vector<float> particles = fluid_block();
    PipelineOptions options = container_options(2);
    options.container.mesh_aabb_min = Vector3{0.1, 0.1, 0.075};  // multiples of the cube edge 0.0125
    options.container.mesh_aabb_max = Vector3{0.5, 0.5, 1.0};
    options.postprocess.mesh_cleanup = true;
    const PipelineResult result = run(particles, options);
    const MeshCheck check = check_mesh(result.mesh);
    INFO(check.summary());
    CHECK(check.ok());
    for (std::size_t v = 0; v < result.mesh.num_vertices(); ++v)
        for (int k = 0; k < 3; ++k) {
            REQUIRE(result.mesh.vertices[3 * v + k] >= static_cast<float>((*options.container.mesh_aabb_min)[k]));
            REQUIRE(result.mesh.vertices[3 * v + k] <= static_cast<float>((*options.container.mesh_aabb_max)[k]));
        }
}

TEST_CASE("capped container: the same bits for 1, 2 and 5 threads", "[container][determinism]") {
    const std::vector<float> particles = fluid_block();
    PipelineOptions options = container_options(1);
    options.postprocess.mesh_cleanup = true;  // every stage that knows the walls
    options.postprocess.output_weights = true;
    const PipelineResult one = run(particles, options);
    REQUIRE(one.mesh.num_triangles() > 0);
    for (const int threads : {2, 5}) {
        options.execution.threads = threads;
        const PipelineResult many = run(particles, options);
        CHECK(mesh_hash(one.mesh) == mesh_hash(many.mesh));
        CHECK(one.mesh.normals == many.mesh.normals);
        CHECK(one.mesh.attributes[0].values == many.mesh.attributes[0].values);
    }
}

TEST_CASE("a mesh box away from the fluid gives an empty mesh and says why", "[container]") {
    const std::vector<float> particles = fluid_block();
    PipelineOptions options = container_options(2);
    for (const bool cap : {true, false}) {
        options.container.mesh_aabb_cap = cap;
        options.container.mesh_aabb_min = Vector3{5.0, 5.0, 5.0};
        options.container.mesh_aabb_max = Vector3{6.0, 6.0, 6.0};
        const PipelineResult result = run(particles, options);
        CHECK(result.mesh.num_triangles() == 0);
        CHECK(result.mesh.num_vertices() == 0);
        REQUIRE(!result.stats.warnings.empty());
        CHECK(result.stats.warnings.back().find("mesh_aabb_min/max") != std::string::npos);
    }
}

TEST_CASE("at a tank wall the free surface keeps the weights of flat fluid", "[container][weights]") {
    // Particles filling [0, 0.8]^2 x [0, 0.4] and ending there, as in a tank whose walls are the box's.
    std::vector<float> particles;
    for (int z = 0; z < 8; ++z)
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x)
                for (double c : {kRadius * (1 + 2 * x), kRadius * (1 + 2 * y), kRadius * (1 + 2 * z)}) particles.push_back(static_cast<float>(c));
    PipelineOptions options = container_options(2);
    options.container.mesh_aabb_min = Vector3{0.0, 0.0, 0.0};
    options.container.mesh_aabb_max = Vector3{0.8, 0.8, 1.0};
    options.postprocess.output_weights = true;
    options.postprocess.smoothing_iterations = 0;
    // The lowest weight on the top surface within a kernel support of the wall x = 0 (off the wall itself).
    const auto lowest_near_wall = [](const TriMesh& mesh) {
        const Attribute* weights = find_attribute(mesh.attributes, "weights");
        REQUIRE(weights != nullptr);
        float lowest = 2.0f;
        for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
            const float* p = &mesh.vertices[3 * v];
            if (p[2] > 0.39f && p[0] > 0.0f && p[0] < 0.1f && p[1] > 0.3f && p[1] < 0.5f) lowest = std::min(lowest, weights->values[v]);
        }
        return lowest;
    };
    const float in_tank = lowest_near_wall(run(particles, options).mesh);
    options.container = ContainerParams{};
    const float free_edge = lowest_near_wall(run(particles, options).mesh);
    INFO("lowest weight next to the wall: " << in_tank << " in the tank, " << free_edge << " at the block's free edge");
    CHECK(in_tank >= 0.99f);
    CHECK(free_edge < 0.95f);  // without the wall the same place is the block's edge: a feature
}

TEST_CASE("a box around all the fluid changes nothing, bit for bit", "[container]") {
    const std::vector<float> particles = fluid_block();
    PipelineOptions options = container_options(2);
    const PipelineResult around = [&] {
        options.container.mesh_aabb_min = Vector3{-1.0, -1.0, -1.0};
        options.container.mesh_aabb_max = Vector3{2.0, 2.0, 2.0};
        return run(particles, options);
    }();
    options.container = ContainerParams{};
    const PipelineResult none = run(particles, options);
    REQUIRE(none.mesh.num_triangles() > 0);
    CHECK(mesh_hash(around.mesh) == mesh_hash(none.mesh));
    CHECK(around.mesh.normals == none.mesh.normals);
}

TEST_CASE("open cut: triangles outside removed and the cut left open, clamping puts the rest on the walls", "[container]") {
    const std::vector<float> particles = fluid_block();
    PipelineOptions options = container_options(2);
    options.container.mesh_aabb_cap = false;
    const PipelineResult cut = run(particles, options);
    const MeshCheck check = check_mesh(cut.mesh);
    CHECK(check.boundary_edges > 0);
    CHECK(check.unreferenced_vertices == 0);
    std::size_t outside_vertices = 0;
    for (std::size_t t = 0; t < cut.mesh.num_triangles(); ++t) {
        int inside = 0;
        for (int c = 0; c < 3; ++c) inside += inside_box(&cut.mesh.vertices[3 * cut.mesh.triangles[3 * t + c]]);
        REQUIRE(inside > 0);
    }
    for (std::size_t v = 0; v < cut.mesh.num_vertices(); ++v) outside_vertices += !inside_box(&cut.mesh.vertices[3 * v]);
    CHECK(outside_vertices > 0);  // the triangles straddling the walls keep their outer vertices
    CHECK(cut.mesh.normals.size() == cut.mesh.vertices.size());

    options.container.mesh_aabb_clamp_verts = true;
    const PipelineResult clamped = run(particles, options);
    CHECK(clamped.mesh.num_triangles() == cut.mesh.num_triangles());
    for (std::size_t v = 0; v < clamped.mesh.num_vertices(); ++v) REQUIRE(inside_box(&clamped.mesh.vertices[3 * v]));
}

TEST_CASE("particle box: particles outside are dropped and counted", "[container]") {
    const std::vector<float> particles = fluid_block();
    PipelineOptions options;
    options.reconstruction = reconstruction_params(kRadius, 0.5);
    options.container.particle_aabb_min = Vector3{-1.0, -1.0, -1.0};
    options.container.particle_aabb_max = Vector3{0.3, 10.0, 10.0};  // keeps the particles with x below 0.3
    std::size_t expected_outside = 0;
    for (std::size_t i = 0; i < particles.size() / 3; ++i) expected_outside += particles[3 * i] > 0.3f;
    const PipelineResult result = run(particles, options);
    const double outside = result.stats.count("particles_outside_box", -1.0), counted = result.stats.count("particles", -1.0);
    CHECK(outside == double(expected_outside));
    CHECK(counted == double(particles.size() / 3 - expected_outside));
    // The surface ends a kernel support beyond the last particle kept (x = 0.275).
    for (std::size_t v = 0; v < result.mesh.num_vertices(); ++v) REQUIRE(result.mesh.vertices[3 * v] < 0.275f + 0.1f);

    options.container.particle_aabb_min = Vector3{5.0, 5.0, 5.0};
    options.container.particle_aabb_max = Vector3{6.0, 6.0, 6.0};
    const PipelineResult none = run(particles, options);
    CHECK(none.mesh.num_triangles() == 0);
    REQUIRE(!none.stats.warnings.empty());
    CHECK(none.stats.warnings.front().find("particle_aabb_min/max") != std::string::npos);
}
