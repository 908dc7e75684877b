#include "surface/reconstruction.h"

#include "sph/particle_box.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/errors.h"
#include "base/memory.h"
#include "base/parallel.h"
#include "surface/level_set.h"

namespace meniscus {

namespace {

bool finite_position(const PositionsView& positions, std::size_t i) {
    return std::isfinite(positions.coord(i, 0)) && std::isfinite(positions.coord(i, 1)) && std::isfinite(positions.coord(i, 2));
}


// Particles outside the container's particle box: dropped, with a count and a warning when none are left. Combines
// with `keep` (the finite particles; empty: all). Returns the particles to keep (empty: all).
std::vector<uint8_t> particles_in_box(const PositionsView& positions, std::vector<uint8_t> keep, const ContainerParams* container,
                                      PipelineStats* stats) {
    if (!container || !container->particle_aabb_min || !container->particle_aabb_max) return keep;
    const Vector3& lower = *container->particle_aabb_min;
    const Vector3& upper = *container->particle_aabb_max;
    if (keep.empty()) keep.assign(positions.count, 1);
    std::size_t outside = 0, kept = 0;
    for (std::size_t i = 0; i < positions.count; ++i) {
        if (!keep[i]) continue;
        const double point[3] = {positions.coord(i, 0), positions.coord(i, 1), positions.coord(i, 2)};
        const bool inside = inside_box(point, lower, upper);
        keep[i] = inside;
        inside ? ++kept : ++outside;
    }
    if (stats) {
        stats->set_count("particles_outside_box", static_cast<double>(outside));
        if (kept == 0 && outside > 0)
            stats->warnings.push_back("all " + std::to_string(outside) +
                                      " particles are outside the particle box (particle_aabb_min/max): the mesh is empty");
    }
    return keep;
}

// Rough upper estimate of the bytes the mesh of this frame needs, from the particle cells on the fluid's boundary
// (cells with a missing face neighbour): each carries about one kernel support squared of surface, meshed with
// about 4 triangles per cube face area; about 140 bytes per triangle cover the mesh, the bricks' pieces before
// stitching and the post-processing's adjacency (and the heat flow's fixed-width rows, ~20 of the 140).
double estimate_mesh_bytes(const ParticleGrid& grid, double cube_edge, int threads, std::size_t* estimated_triangles) {
    const std::size_t boundary_cells = parallel_count(static_cast<int64_t>(grid.num_cells()), threads, [&](int64_t cell) {
        const auto c = grid.cell_coords(static_cast<std::size_t>(cell));
        int neighbours = 0;
        const int64_t offsets[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        for (const auto& o : offsets)
            grid.for_each_cell_in_box({c[0] + o[0], c[1] + o[1], c[2] + o[2]}, {c[0] + o[0], c[1] + o[1], c[2] + o[2]},
                                      [&](std::size_t) { ++neighbours; });
        return neighbours < 6;
    });
    const double ratio = grid.cell_size() / cube_edge;
    const double triangles = 4.0 * double(boundary_cells) * ratio * ratio;
    if (estimated_triangles) *estimated_triangles = static_cast<std::size_t>(std::min(triangles, 1e18));
    return triangles * 140.0;
}

}  // namespace

std::vector<uint8_t> finite_particles(const PositionsView& positions, const ExecutionOptions& execution, PipelineStats* stats) {
    std::size_t invalid = 0, first_invalid = 0;
    for (std::size_t i = 0; i < positions.count; ++i)
        if (!finite_position(positions, i) && invalid++ == 0) first_invalid = i;
    if (invalid == 0) return {};
    if (!execution.skip_invalid)
        throw InputError(std::to_string(invalid) + " of " + std::to_string(positions.count) +
                         " particles have NaN or Inf coordinates (the first is particle " + std::to_string(first_invalid) +
                         "); pass skip_invalid (--skip-invalid) to drop them");
    std::vector<uint8_t> keep(positions.count);
    for (std::size_t i = 0; i < positions.count; ++i) keep[i] = finite_position(positions, i);
    if (stats) stats->warnings.push_back("dropped " + std::to_string(invalid) + " particles with NaN or Inf coordinates");
    return keep;
}

SurfaceReconstruction reconstruct_surface(const PositionsView& positions, const ReconstructionParams& params,
                                          const ExecutionOptions& execution, PipelineStats* stats, const ContainerParams* container) {
    validate(params);
    const int threads = resolve_threads(execution.threads);
    const std::vector<uint8_t> keep = particles_in_box(positions, finite_particles(positions, execution, stats), container, stats);
    const double support = params.compact_support();
    const double cube = params.cube_edge();

    StageTimer grid_timer(stats, "neighborhood");
    SurfaceReconstruction r{params, ParticleGrid(positions, support, threads, keep.empty() ? nullptr : &keep), {}, {}};
    grid_timer.stop();

    std::size_t estimated_triangles = 0;
    const double estimate = estimate_mesh_bytes(r.grid, cube, threads, &estimated_triangles);
    check_memory_budget(estimate, execution.memory_budget_bytes(),
                        "the surface mesh at cube size " + format_number(params.cube_size) + " r (about " + std::to_string(estimated_triangles) +
                            " triangles)");

    StageTimer density_timer(stats, "density");
    r.densities = compute_densities(r.grid, CubicSplineKernel(support), threads);
    density_timer.stop();

    StageTimer mc_timer(stats, "level set and marching cubes");
    const std::vector<LatticeCoords> bricks = bricks_near_particles(r.grid, support, cube, threads);
    MeshBox walls;
    const bool capped = container && container->mesh_aabb_min && container->mesh_aabb_max && container->mesh_aabb_cap;
    if (capped) walls = {*container->mesh_aabb_min, *container->mesh_aabb_max};
    r.mesh = mesh_bricks(bricks, colour_field_sampler(r.sph_field(), cube, params.iso_threshold), cube, params.iso_threshold, threads,
                         capped ? &walls : nullptr);
    mc_timer.stop();

    if (stats) {
        stats->set_count("particles", static_cast<double>(r.grid.size()));
        stats->set_count("active_bricks", static_cast<double>(bricks.size()));
        stats->set_count("raw_vertices", static_cast<double>(r.mesh.num_vertices()));
        stats->set_count("raw_triangles", static_cast<double>(r.mesh.num_triangles()));
    }
    return r;
}

}  // namespace meniscus
