#include "pipeline.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "base/errors.h"
#include "mesh/adjacency.h"
#include "base/parallel.h"
#include "post/heat_smoothing.h"
#include "post/postprocess.h"
#include "surface/reconstruction.h"
#include "post/volume.h"
#include "post/weights.h"

namespace meniscus {

namespace {

// Last line of defence for the host application: every vertex must be finite and near the particles (a single
// vertex thrown far away makes renderers abort). Post-processing only averages positions, so this never triggers
// unless a stage is wrong; it then repairs the vertex and says so rather than handing over a dangerous mesh.
void guard_vertices(TriMesh& mesh, const SurfaceReconstruction& r, PipelineStats& stats) {
    if (r.grid.size() == 0) return;
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (std::size_t j = 0; j < r.grid.size(); ++j)
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], r.grid.position(j)[k]);
            hi[k] = std::max(hi[k], r.grid.position(j)[k]);
        }
    const float margin = static_cast<float>(r.params.compact_support() + 2.0 * r.params.cube_edge());
    std::size_t repaired = 0;
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        bool bad = false;
        for (int k = 0; k < 3; ++k) {
            float& x = mesh.vertices[3 * v + k];
            if (!std::isfinite(x) || x < lo[k] - margin || x > hi[k] + margin) {
                bad = true;
                x = std::isfinite(x) ? std::min(std::max(x, lo[k] - margin), hi[k] + margin) : 0.5f * (lo[k] + hi[k]);
            }
        }
        repaired += bad;
    }
    for (float& n : mesh.normals)
        if (!std::isfinite(n)) n = 0.0f;
    if (repaired) stats.warnings.push_back("internal: " + std::to_string(repaired) + " vertices were outside the particles' reach and were clamped");
}

}  // namespace

PipelineResult run_pipeline(const PositionsView& positions, const std::vector<AttributeInput>& attributes, const PipelineOptions& options) {
    validate(static_cast<const Parameters&>(options));
    for (const auto& a : attributes) {
        if (a.components < 1 || a.components > 16)
            throw InputError("attribute '" + a.name + "' must have 1 to 16 components, got " + std::to_string(a.components));
        if (!a.values && positions.count > 0) throw InputError("attribute '" + a.name + "' has no data");
    }
    const int threads = resolve_threads(options.execution.threads);
    const PostprocessParams& post = options.postprocess;

    PipelineResult result;
    PipelineStats& stats = result.stats;
    if (positions.count == 0) stats.warnings.push_back("no particles: the mesh is empty");
    SurfaceReconstruction r = reconstruct_surface(positions, options.reconstruction, options.execution, &stats);
    TriMesh& mesh = r.mesh;
    if (options.keep_raw_mesh) result.raw_mesh = mesh;

    if (post.mesh_cleanup) {
        StageTimer timer(&stats, "mesh cleanup");
        const std::size_t removed = mesh_cleanup(mesh, options.reconstruction.cube_edge(), post.mesh_cleanup_snap_distance, threads);
        stats.set_count("cleanup_removed_vertices", static_cast<double>(removed));
    }
    MeshAdjacency adjacency;
    bool have_adjacency = false;
    if (post.decimate_barnacles) {
        StageTimer timer(&stats, "decimation");
        const std::size_t removed = decimate_barnacles(mesh, threads, &adjacency);
        have_adjacency = adjacency.vertex_triangles.rows() == mesh.num_vertices() && mesh.num_vertices() > 0;
        stats.set_count("decimated_configurations", static_cast<double>(removed));
    }

    // From here on the topology stays as it is: one adjacency serves smoothing, restoration and normals.
    if (!have_adjacency) {
        StageTimer adjacency_timer(&stats, "adjacency");
        adjacency = build_adjacency(mesh, threads);
    }

    std::vector<float> weights;
    const bool need_weights = (post.smoothing_iterations > 0 && post.smoothing_weights) || post.output_weights;
    if (need_weights) {
        StageTimer timer(&stats, "weights");
        result.weights_normalization = halfspace_normalization(r, post.weights_normalization);
        weights = feature_weights(r, mesh.vertices, result.weights_normalization, post.weights_smoothstep, threads);
        stats.set_count("weights_normalization", result.weights_normalization);
    }
    if (post.output_weights) mesh.attributes.push_back({"weights", 1, weights});
    bool normals_from_restoration = false;  // volume restoration left the normals the output asks for
    if (post.smoothing_iterations > 0 && !post.smoothing_explicit) {
        // Heat flow of a physical reach with local volume return and a final per-component correction (heat_smoothing.h).
        StageTimer timer(&stats, "smoothing");
        const double radius = options.reconstruction.particle_radius;
        HeatSmoothingSettings settings;
        settings.reach = smoothing_reach_of(post.smoothing_iterations, post.smoothing_strength, options.reconstruction.cube_size,
                                            kSmoothingCoarseFloor) * radius;
        settings.particle_radius = radius;
        settings.volume_correction = post.volume_restoration;
        const bool output_normals = post.normals && !post.sph_normals && post.normal_smoothing_iterations > 0;
        settings.normal_iterations = output_normals ? post.normal_smoothing_iterations : 10;
        settings.max_offset = options.reconstruction.compact_support();
        settings.walls = nullptr;  // the container box's walls (post/wall_constraints.h) go here once it makes them
        const HeatSmoothingReport report =
            heat_smooth(mesh, adjacency, post.smoothing_weights ? weights : std::vector<float>{}, settings, threads);
        normals_from_restoration = output_normals && report.normals_left;
        stats.set_count("smoothing_reach", settings.reach / radius);
        stats.set_count("smoothing_equivalent_iterations", report.iterations);
        stats.set_count("smoothing_applications", report.applications);
        if (report.reverted_components) stats.set_count("components_left_unsmoothed", static_cast<double>(report.reverted_components));
    } else if (post.smoothing_iterations > 0) {
        StageTimer timer(&stats, "smoothing");
        const std::vector<float> smoothing_amount = post.smoothing_weights ? weights : std::vector<float>{};
        int32_t components = 0;
        const std::vector<int32_t> labels = component_labels(mesh, &components);
        const std::vector<double> volumes = component_volumes(mesh, labels, components, threads);
        const std::vector<float> before = mesh.vertices;
        laplacian_smooth(mesh, adjacency, smoothing_amount, post.smoothing_iterations, post.smoothing_strength, threads);
        timer.stop();
        if (post.volume_restoration) {
            StageTimer restoration_timer(&stats, "volume restoration");
            // Offsets along the smoothed normals the output asks for (Eq. 12 with its iteration count), which then
            // are the output normals; otherwise (SPH, unsmoothed or no normals) along 10 smoothing iterations.
            normals_from_restoration = post.normals && !post.sph_normals && post.normal_smoothing_iterations > 0;
            restore_component_volumes(mesh, adjacency, labels, volumes, smoothing_amount, options.reconstruction.compact_support(),
                                      normals_from_restoration ? post.normal_smoothing_iterations : 10, threads);
        }
        const std::size_t reverted = revert_collapsed_components(mesh, before, labels, components, volumes, threads);
        if (reverted) {
            stats.set_count("components_left_unsmoothed", static_cast<double>(reverted));
            normals_from_restoration = false;  // reverted vertices moved: their normals are recomputed below
        }
    }

    if (post.normals) {
        StageTimer timer(&stats, "normals");
        if (post.sph_normals) {
            mesh.normals = colour_field_normals(r, mesh.vertices, threads);
        } else if (!normals_from_restoration) {
            compute_area_weighted_normals(mesh, adjacency, threads);
            if (post.normal_smoothing_iterations > 0) smooth_normals(mesh, adjacency, post.normal_smoothing_iterations, threads);
        }
    } else {
        mesh.normals.clear();
    }

    if (!attributes.empty()) {
        StageTimer timer(&stats, "attributes");
        for (const auto& a : attributes) {
            Attribute out{a.name, a.components, {}, a.integral};
            if (a.integral)
                nearest_particle_at_points(r, a.values, a.components, mesh.vertices, out.values, threads);
            else
                interpolate_at_points(r, a.values, a.components, mesh.vertices, out.values, threads);
            mesh.attributes.push_back(std::move(out));
        }
    }
    guard_vertices(mesh, r, stats);
    stats.set_count("vertices", static_cast<double>(mesh.num_vertices()));
    stats.set_count("triangles", static_cast<double>(mesh.num_triangles()));
    result.mesh = std::move(mesh);
    return result;
}

}  // namespace meniscus
