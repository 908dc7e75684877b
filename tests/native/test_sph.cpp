// The SPH building blocks (sph/): the kernel, the neighbour search and the interpolation onto mesh vertices.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "base/numbers.h"
#include "io/io.h"
#include "mesh_builders.h"
#include "pipeline.h"
#include "sph/kernel.h"
#include "sph/neighborhood.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("cubic spline kernel integrates to one and vanishes at the support", "[kernel]") {
    for (double support : {0.1, 1.0, 4.0}) {
        CubicSplineKernel kernel(support);
        const int steps = 20000;
        double integral = 0.0;
        for (int i = 0; i < steps; ++i) {
            const double d = (i + 0.5) * support / steps;
            integral += 4.0 * kPi * d * d * kernel.value(static_cast<float>(d)) * support / steps;
        }
        CHECK(integral == Approx(1.0).epsilon(1e-4));
        CHECK(kernel.value(static_cast<float>(support)) == 0.0f);
        CHECK(kernel.value(static_cast<float>(0.5 * support)) > 0.0f);
        // The derivative matches a finite difference.
        const float d = static_cast<float>(0.3 * support), h = static_cast<float>(1e-3 * support);
        CHECK(kernel.derivative(d) == Approx((kernel.value(d + h) - kernel.value(d - h)) / (2 * h)).epsilon(1e-2));
    }
}

TEST_CASE("neighbour search finds exactly the brute-force neighbours", "[neighborhood]") {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<float> points(3 * 3000);
    for (float& x : points) x = u(rng);
    const float radius = 0.15f;
    ParticleGrid grid(PositionsView(points.data(), 3000), radius, 2);
    REQUIRE(grid.size() == 3000);
    for (int q = 0; q < 200; ++q) {
        const float x[3] = {u(rng), u(rng), u(rng)};
        std::vector<uint32_t> found, expected;
        grid.for_each_neighbor(x, radius, [&](std::size_t j, float) { found.push_back(grid.original_index(j)); });
        for (uint32_t i = 0; i < 3000; ++i) {
            const float dx = x[0] - points[3 * i], dy = x[1] - points[3 * i + 1], dz = x[2] - points[3 * i + 2];
            if (dx * dx + dy * dy + dz * dz < radius * radius) expected.push_back(i);
        }
        std::sort(found.begin(), found.end());
        REQUIRE(found == expected);
    }
}

TEST_CASE("attributes are interpolated with the Shepard correction", "[reconstruction][attributes]") {
    const ParticleData particles = read_particles(shared_frame("splashsurf/bunny_frame_14_7705_particles.vtk"));
    // A constant attribute must come out exactly constant (0th-order correction), a linear one close to linear.
    std::vector<float> constant(particles.size() * 3, 0.0f), linear(particles.size());
    for (std::size_t i = 0; i < particles.size(); ++i) {
        constant[3 * i] = 2.5f;
        constant[3 * i + 1] = -1.0f;
        linear[i] = particles.positions[3 * i + 2];
    }
    PipelineOptions options;
    options.reconstruction = reconstruction_params(0.025, 1.0);
    const PipelineResult result = run_pipeline(PositionsView(particles.positions.data(), particles.size()),
                                               {{"c", constant.data(), 3}, {"z", linear.data(), 1}}, options);
    REQUIRE(result.mesh.attributes.size() == 2);
    const Attribute& c = result.mesh.attributes[0];
    const Attribute& z = result.mesh.attributes[1];
    REQUIRE(c.count() == result.mesh.num_vertices());
    double worst = 0.0, mean_error = 0.0;
    for (std::size_t v = 0; v < result.mesh.num_vertices(); ++v) {
        worst = std::max(worst, std::fabs(c.values[3 * v] - 2.5));
        mean_error += std::fabs(z.values[v] - result.mesh.vertices[3 * v + 2]) / double(result.mesh.num_vertices());
    }
    CHECK(worst < 1e-5);
    CHECK(mean_error < 0.05);  // within the kernel support (0.1)
}
