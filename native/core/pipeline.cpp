#include "pipeline.h"

#include <string>
#include <utility>

#include "base/parallel.h"
#include "mesh/adjacency.h"
#include "post/decimation.h"
#include "post/heat_smoothing.h"
#include "post/mesh_cleanup.h"
#include "post/normals.h"
#include "post/quads.h"
#include "post/smoothing.h"
#include "post/stray_filter.h"
#include "post/vertex_guard.h"
#include "post/volume.h"
#include "post/weights.h"
#include "sph/interpolation.h"
#include "surface/reconstruction.h"

namespace meniscus {

PipelineResult run_pipeline(const PositionsView& positions, const std::vector<AttributeInput>& attributes, const PipelineOptions& options) {
    validate(static_cast<const Parameters&>(options));
    validate_attribute_inputs(attributes, positions.count);
    const ReconstructionParams& surface = options.reconstruction;
    const PostprocessParams& post = options.postprocess;
    const int threads = resolve_threads(options.execution.threads);
    PipelineResult result;
    PipelineStats& stats = result.stats;
    if (positions.count == 0) stats.warnings.push_back("no particles: the mesh is empty");

    // Particles -> marching-cubes mesh (its stages time themselves: neighborhood, density, level set and marching cubes).
    SurfaceReconstruction reconstruction = reconstruct_surface(positions, surface, options.execution, &stats);
    const SphField particles = reconstruction.sph_field();
    TriMesh mesh = std::move(reconstruction.mesh);
    if (options.keep_raw_mesh) result.raw_mesh = mesh;

    // Stray blobs, judged on the marching-cubes mesh by their particle count or enclosed volume (off by default).
    if (post.stray_min_particles > 0 || post.stray_min_volume > 0.0) {
        StageTimer timer(&stats, "stray blobs");
        const StrayRemoval strays = remove_stray_components(mesh, reconstruction, post.stray_min_particles, post.stray_min_volume, threads);
        stats.set_count("stray_components_removed", static_cast<double>(strays.components));
        stats.set_count("stray_particles_removed", static_cast<double>(strays.particles));
        stats.set_count("stray_volume_removed", strays.volume);
    }

    // Mesh cleanup and barnacle decimation (Sec. 3.3): the slivers marching cubes leaves at grid points.
    if (post.mesh_cleanup) {
        StageTimer timer(&stats, "mesh cleanup");
        const std::size_t removed = mesh_cleanup(mesh, surface.cube_edge(), post.mesh_cleanup_snap_distance, threads);
        stats.set_count("cleanup_removed_vertices", static_cast<double>(removed));
    }

    MeshAdjacency adjacency;
    if (post.decimate_barnacles) {
        StageTimer timer(&stats, "decimation");
        const std::size_t removed = decimate_barnacles(mesh, threads, &adjacency);
        stats.set_count("decimated_configurations", static_cast<double>(removed));
    }

    // From here on the topology stays as it is: one adjacency serves smoothing, restoration and normals, built only
    // when one of them runs. Decimation hands over the one its last pass built, when it could (rows for every vertex
    // of a non-empty mesh).
    const bool needs_adjacency = post.smoothing_iterations > 0 || (post.normals && !post.sph_normals);
    const bool handed_over = mesh.num_vertices() > 0 && adjacency.vertex_triangles.rows() == mesh.num_vertices();
    if (!needs_adjacency) {
        adjacency = MeshAdjacency{};  // decimation's, if any: not kept for nothing
    } else if (!handed_over) {
        StageTimer timer(&stats, "adjacency");
        adjacency = build_adjacency(mesh, threads);
    }

    // Feature weights (Sec. 3.2): how strongly each vertex is smoothed.
    std::vector<float> weights;
    if ((post.smoothing_iterations > 0 && post.smoothing_weights) || post.output_weights) {
        StageTimer timer(&stats, "weights");
        const std::vector<float>& counts = reconstruction.densities.neighbor_counts;
        result.weights_normalization = halfspace_normalization(counts, surface.iso_threshold, post.weights_normalization);
        weights = feature_weights(particles, counts, mesh.vertices, result.weights_normalization, post.weights_smoothstep, threads);
        stats.set_count("weights_normalization", result.weights_normalization);
    }
    if (post.output_weights) mesh.attributes.push_back({"weights", 1, weights});
    const std::vector<float> smoothing_amount = post.smoothing_weights ? std::move(weights) : std::vector<float>{};

    // Smoothing, remembering the surface it started from: the paper's explicit iterations (Eq. 3-5), or on request a
    // heat flow of a physical reach that returns its local shrinkage where it happened (post/heat_smoothing.h).
    UnsmoothedSurface unsmoothed;
    SmoothedNormals restoration_normals;
    const bool heat = post.smoothing_iterations > 0 && post.smoothing_reach > 0.0;
    if (post.smoothing_iterations > 0) {
        StageTimer timer(&stats, "smoothing");
        unsmoothed = record_unsmoothed_surface(mesh, threads);
        if (heat) {
            const double radius = surface.particle_radius;
            HeatSmoothingSettings settings;
            settings.reach = smoothing_reach_at(post.smoothing_reach, surface.cube_size) * radius;
            settings.particle_radius = radius;
            settings.volume_correction = post.volume_restoration;
            settings.normal_iterations = restoration_normal_iterations(post);
            settings.max_offset = surface.compact_support();
            settings.walls = nullptr;  // the container box's walls (post/wall_constraints.h) go here once it makes them
            const HeatSmoothingReport report = heat_smooth(mesh, adjacency, smoothing_amount, settings, unsmoothed, threads);
            // Its final correction moved the vertices along these normals; the normals stage takes them when they fit.
            restoration_normals = report.normals;
            stats.set_count("smoothing_reach", settings.reach / radius);
            stats.set_count("smoothing_equivalent_iterations", report.iterations);
            stats.set_count("smoothing_applications", report.applications);
        } else {
            laplacian_smooth(mesh, adjacency, smoothing_amount, post.smoothing_iterations, post.smoothing_strength, threads);
        }
    }

    // Volume restoration: each component's volume back, along smoothed normals the normals stage may take (the heat
    // flow makes its own, smaller correction above).
    if (post.smoothing_iterations > 0 && post.volume_restoration && !heat) {
        StageTimer timer(&stats, "volume restoration");
        restoration_normals = restore_component_volumes(mesh, adjacency, unsmoothed, smoothing_amount, surface.compact_support(),
                                                        restoration_normal_iterations(post), threads);
    }

    // The collapse guard: a component that smoothing collapsed gets its unsmoothed positions back.
    if (post.smoothing_iterations > 0) {
        const std::size_t reverted = revert_collapsed_components(mesh, unsmoothed, threads);
        if (reverted > 0) {
            stats.set_count("components_left_unsmoothed", static_cast<double>(reverted));
            restoration_normals = SmoothedNormals{};  // reverted vertices moved: those normals no longer fit
        }
    }

    // Normals (Sec. 3.4): the colour field's gradient, or area-weighted and smoothed by Eq. 12.
    if (post.normals) {
        StageTimer timer(&stats, "normals");
        mesh.normals = post.sph_normals ? colour_field_normals(particles, mesh.vertices, threads)
                                        : smoothed_vertex_normals(mesh, adjacency, post.normal_smoothing_iterations,
                                                                  std::move(restoration_normals), threads);
    }

    // Particle attributes onto the final vertices (Eq. 7, or the nearest particle's for whole numbers).
    if (!attributes.empty()) {
        StageTimer timer(&stats, "attributes");
        for (Attribute& transferred : transfer_attributes(particles, attributes, mesh.vertices, threads))
            mesh.attributes.push_back(std::move(transferred));
    }

    // Quads last: merging faces moves no vertex, so normals and attributes stay as they are.
    if (post.generate_quads) {
        StageTimer timer(&stats, "quads");
        const QuadCriteria criteria{post.quad_max_edge_diag_ratio, post.quad_max_normal_angle, post.quad_max_interior_angle};
        stats.set_count("quads", static_cast<double>(merge_triangles_into_quads(mesh, criteria, threads)));
    }

    // The last line of defence for the host application (post/vertex_guard.h).
    const std::size_t clamped = keep_vertices_near_particles(mesh, reconstruction.grid, surface.compact_support() + 2.0 * surface.cube_edge());
    if (clamped > 0)
        stats.warnings.push_back("internal: " + std::to_string(clamped) + " vertices were outside the particles' reach and were clamped");
    stats.set_count("vertices", static_cast<double>(mesh.num_vertices()));
    stats.set_count("triangles", static_cast<double>(mesh.num_triangles()));
    result.mesh = std::move(mesh);
    return result;
}

}  // namespace meniscus
