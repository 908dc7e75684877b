#include "pipeline.h"

#include <algorithm>
#include <string>
#include <utility>

#include "base/errors.h"
#include "base/machine_load.h"
#include "base/parallel.h"
#include "mesh/adjacency.h"
#include "post/container.h"
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
#include "sph/interior_fill.h"
#include "sph/interpolation.h"
#include "surface/particle_level_set.h"
#include "surface/reconstruction.h"

namespace meniscus {

namespace {

// The particles with the narrow-band fill's after them (sph/interior_fill.h), each fill particle taking its source
// particle's attributes; the positions keep the caller's precision.
struct FilledParticles {
    std::vector<float> f32;
    std::vector<double> f64;
    std::vector<std::vector<float>> attribute_values;
    std::vector<AttributeInput> attributes;
    PositionsView view;
};

// Whether a setting that is 1 on, 0 off and -1 automatic (on for a narrow band's domain) is on; InputError, starting
// with `on_text`, when it is on and the particles come without their fluid domain.
bool on_for_narrow_band(int setting, const char* on_text, const PipelineOptions& options) {
    if (setting == 1 && !options.fluid_domain)
        throw InputError(std::string(on_text) + ", but the particles come without their fluid domain (a grid solver's cache such as "
                         "Mantaflow's carries one): use automatic or 0");
    return options.fluid_domain && (setting == 1 || (setting == -1 && narrow_band_domain(*options.fluid_domain)));
}

bool wants_fill(const PipelineOptions& options) { return on_for_narrow_band(options.reconstruction.fill_interior, "fill_interior is on", options); }

bool wants_level_set(const PipelineOptions& options) {
    return on_for_narrow_band(options.reconstruction.fluid_surface, "fluid_surface is 1 (Mantaflow's level set)", options);
}

void fill_narrow_band(const PositionsView& positions, const std::vector<AttributeInput>& attributes, const PipelineOptions& options,
                      FilledParticles& out, PipelineStats& stats) {
    StageTimer timer(&stats, "interior fill");
    InteriorFill fill = fill_interior(positions, *options.fluid_domain, 2.0 * options.reconstruction.particle_radius,
                                      options.execution.threads, options.execution.memory_budget_bytes());
    const std::size_t n = positions.count, added = fill.source.size();
    const InteriorClassification& cells = fill.classification;
    stats.set_count("interior_fill_particles", static_cast<double>(added));
    stats.set_count("interior_fill_liquid_cells", static_cast<double>(cells.count(CellClass::liquid)));
    stats.set_count("interior_fill_shell_cells", static_cast<double>(cells.count(CellClass::shell)));
    stats.set_count("interior_fill_regions_split", static_cast<double>(cells.split_components));
    // Each of the fill's arrays is released as soon as it is copied: at resolution 512 they are gigabytes.
    std::vector<CellClass>().swap(fill.classification.cells);
    if (positions.f64) {
        out.f64.reserve(3 * (n + added));
        out.f64.assign(positions.f64, positions.f64 + 3 * n);
        out.f64.insert(out.f64.end(), fill.positions.begin(), fill.positions.end());
        out.view = PositionsView(out.f64.data(), n + added);
    } else {
        out.f32.reserve(3 * (n + added));
        out.f32.assign(positions.f32, positions.f32 + 3 * n);
        out.f32.insert(out.f32.end(), fill.positions.begin(), fill.positions.end());
        out.view = PositionsView(out.f32.data(), n + added);
    }
    std::vector<float>().swap(fill.positions);
    out.attribute_values.reserve(attributes.size());
    for (const AttributeInput& a : attributes) {
        const std::size_t k = static_cast<std::size_t>(a.components);
        std::vector<float> values;
        values.reserve(k * (n + added));
        values.assign(a.values, a.values + k * n);
        values.resize(k * (n + added));
        for (std::size_t f = 0; f < added; ++f)
            std::copy(a.values + k * fill.source[f], a.values + k * (fill.source[f] + 1), values.begin() + k * (n + f));
        out.attribute_values.push_back(std::move(values));
        out.attributes.push_back({a.name, out.attribute_values.back().data(), a.components, a.integral});
    }
}

// Mantaflow's own surface (surface/particle_level_set.h) and the stages that keep it Mantaflow's: no cleanup,
// decimation or smoothing (Mantaflow does not smooth its mesh after marching cubes, and the smoothing's reach
// would take volume from it), normals and attributes as on every mesh, the open mesh box, quads.
PipelineResult level_set_pipeline(const PositionsView& positions, const std::vector<AttributeInput>& attributes, const PipelineOptions& options,
                                  int threads) {
    PipelineResult result;
    PipelineStats& stats = result.stats;
    stats.set_count("threads", threads);
    stats.set_count("particles", static_cast<double>(positions.count));
    if (positions.count == 0) stats.warnings.push_back("no particles: the mesh is empty");
    finite_particles(positions, options.execution, &stats);  // refused, or left out by the level set when skipped
    ParticleLevelSetSurface surface;
    {
        StageTimer timer(&stats, "particle level set");
        surface = particle_level_set_surface(positions, attributes, *options.fluid_domain, threads, options.execution.memory_budget_bytes());
    }
    stats.set_count("level_set_cells", double(surface.resolution[0]) * surface.resolution[1] * surface.resolution[2]);
    stats.set_count("level_set_joined_cells", static_cast<double>(surface.joined_cells));
    TriMesh mesh = std::move(surface.mesh);
    if (options.keep_raw_mesh) result.raw_mesh = mesh;
    const PostprocessParams& post = options.postprocess;
    if (post.normals) {
        StageTimer timer(&stats, "normals");
        const MeshAdjacency adjacency = build_adjacency(mesh, threads);
        mesh.normals = smoothed_vertex_normals(mesh, adjacency, post.normal_smoothing_iterations, SmoothedNormals{}, threads);
    }
    const ContainerParams& container = options.container;
    if (container.mesh_aabb_min && container.mesh_aabb_max && !container.mesh_aabb_cap) {
        StageTimer timer(&stats, "container");
        stats.set_count("container_removed_triangles", static_cast<double>(cut_open_at_box(
                                                           mesh, *container.mesh_aabb_min, *container.mesh_aabb_max, container.mesh_aabb_clamp_verts)));
    }
    if (post.generate_quads) {
        StageTimer timer(&stats, "quads");
        const QuadCriteria criteria{post.quad_max_edge_diag_ratio, post.quad_max_normal_angle, post.quad_max_interior_angle};
        stats.set_count("quads", static_cast<double>(merge_triangles_into_quads(mesh, criteria, threads)));
    }
    stats.set_count("vertices", static_cast<double>(mesh.num_vertices()));
    stats.set_count("triangles", static_cast<double>(mesh.num_triangles()));
    result.mesh = std::move(mesh);
    return result;
}

}  // namespace

PipelineResult run_pipeline(const PositionsView& given_positions, const std::vector<AttributeInput>& given_attributes, const PipelineOptions& options) {
    validate(static_cast<const Parameters&>(options));
    validate_attribute_inputs(given_attributes, given_positions.count);
    if (options.execution.threads == 0) {  // automatic: the cores free as the frame starts (base/machine_load.h)
        PipelineOptions chosen = options;
        chosen.execution.threads = automatic_frame_threads();
        return run_pipeline(given_positions, given_attributes, chosen);
    }
    if (wants_level_set(options)) return level_set_pipeline(given_positions, given_attributes, options, resolve_threads(options.execution.threads));
    PipelineResult result;
    // The narrow-band fill: solid water from a shell of particles, before anything else sees them.
    FilledParticles filled;
    const bool fill = wants_fill(options);
    if (fill) fill_narrow_band(given_positions, given_attributes, options, filled, result.stats);
    const PositionsView& positions = fill ? filled.view : given_positions;
    const std::vector<AttributeInput>& attributes = fill ? filled.attributes : given_attributes;
    const ReconstructionParams& surface = options.reconstruction;
    const PostprocessParams& post = options.postprocess;
    const int threads = resolve_threads(options.execution.threads);
    PipelineStats& stats = result.stats;
    stats.set_count("threads", threads);
    if (positions.count == 0) stats.warnings.push_back("no particles: the mesh is empty");

    // Particles -> marching-cubes mesh (its stages time themselves: neighborhood, density, level set and marching cubes).
    // The container's particle box drops particles there; a capped mesh box closes the surface on its walls.
    const ContainerParams& container = options.container;
    const bool mesh_box = container.mesh_aabb_min && container.mesh_aabb_max;
    const bool capped = mesh_box && container.mesh_aabb_cap;
    SurfaceReconstruction reconstruction = reconstruct_surface(positions, surface, options.execution, &stats, &container);
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

    // Capped: the vertices on the walls, held there by every later stage. Cleanup and decimation leave them in place
    // (pinned), so after each they are found again by their exact coordinates. None (a box around all the fluid):
    // an empty mask, and every stage runs as without a box.
    WallConstraints walls;
    const auto find_walls = [&] {
        if (!capped) return;
        walls = find_wall_vertices(mesh, *container.mesh_aabb_min, *container.mesh_aabb_max, threads);
        if (std::none_of(walls.mask.begin(), walls.mask.end(), [](uint8_t faces) { return faces != 0; })) walls.mask.clear();
    };
    find_walls();
    if (!walls.empty()) stats.set_count("container_edge_vertices", static_cast<double>(square_box_edges(mesh, walls)));
    const auto pinned = [&] { return walls.empty() ? nullptr : &walls.mask; };

    // Mesh cleanup and barnacle decimation (Sec. 3.3): the slivers marching cubes leaves at grid points.
    if (post.mesh_cleanup) {
        StageTimer timer(&stats, "mesh cleanup");
        const std::size_t removed = mesh_cleanup(mesh, surface.cube_edge(), post.mesh_cleanup_snap_distance, threads, pinned());
        stats.set_count("cleanup_removed_vertices", static_cast<double>(removed));
        find_walls();
    }

    MeshAdjacency adjacency;
    if (post.decimate_barnacles) {
        StageTimer timer(&stats, "decimation");
        const std::size_t removed = decimate_barnacles(mesh, threads, &adjacency, pinned());
        stats.set_count("decimated_configurations", static_cast<double>(removed));
        find_walls();
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
        result.weights_normalization = halfspace_normalization(counts, surface.iso_threshold, post.weights_normalization, threads);
        // N_HS from the particles as they are; the counts the weights read, mirrored at the walls (post/container.h).
        const std::vector<float> mirrored = walls.empty() ? std::vector<float>{}
                                                          : counts_mirrored_at_walls(reconstruction.grid, counts, *container.mesh_aabb_min,
                                                                                     *container.mesh_aabb_max, surface.compact_support(), threads);
        weights = feature_weights(particles, walls.empty() ? counts : mirrored, mesh.vertices, result.weights_normalization,
                                  post.weights_smoothstep, threads);
        stats.set_count("weights_normalization", result.weights_normalization);
    }
    if (post.output_weights) mesh.attributes.push_back({"weights", 1, weights});
    std::vector<float> smoothing_amount = post.smoothing_weights ? std::move(weights) : std::vector<float>{};
    if (!walls.empty() && post.smoothing_iterations > 0)
        smoothing_amount = smoothing_amount_at_walls(walls, std::move(smoothing_amount));

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
            settings.walls = walls.empty() ? nullptr : &walls;  // capped: wall vertices slide along their walls
            const HeatSmoothingReport report = heat_smooth(mesh, adjacency, smoothing_amount, settings, unsmoothed, threads);
            // Its final correction moved the vertices along these normals; the normals stage takes them when they fit.
            restoration_normals = report.normals;
            stats.set_count("smoothing_reach", settings.reach / radius);
            stats.set_count("smoothing_equivalent_iterations", report.iterations);
            stats.set_count("smoothing_applications", report.applications);  // on the mesh
            stats.set_count("smoothing_aggregates", static_cast<double>(report.aggregates));
            stats.set_count("smoothing_parts", report.parts);
            stats.set_count("smoothing_coarse_applications", report.coarse_applications);  // on the aggregates
            // Its three phases, to see which one limits the scaling (bench/scaling.py): not stages, so not in the total.
            stats.set_count("smoothing_flow_seconds", report.seconds_flow);
            stats.set_count("smoothing_return_seconds", report.seconds_return);
            stats.set_count("smoothing_correction_seconds", report.seconds_correction);
        } else {
            MeshAdjacency along_walls;  // capped: the contact line smoothed along itself (post/container.h)
            if (!walls.empty()) along_walls.vertex_neighbours = smoothing_neighbours_at_walls(walls, adjacency.vertex_neighbours);
            laplacian_smooth(mesh, walls.empty() ? adjacency : along_walls, smoothing_amount, post.smoothing_iterations, post.smoothing_strength, threads,
                             walls.empty() ? nullptr : &walls);
        }
    }

    // Volume restoration: each component's volume back, along smoothed normals the normals stage may take (the heat
    // flow makes its own, smaller correction above).
    if (post.smoothing_iterations > 0 && post.volume_restoration && !heat) {
        StageTimer timer(&stats, "volume restoration");
        // Vertices on a wall do not move along normals (which leave the wall): the rest of the surface restores the
        // volume, so the step's estimate must not count their area.
        std::vector<float> amount;
        if (!walls.empty()) {
            amount = smoothing_amount.empty() ? std::vector<float>(mesh.num_vertices(), 1.0f) : smoothing_amount;
            for (std::size_t v = 0; v < walls.mask.size(); ++v)
                if (walls.mask[v]) amount[v] = 0.0f;
        }
        restoration_normals = restore_component_volumes(mesh, adjacency, unsmoothed, walls.empty() ? smoothing_amount : amount, surface.compact_support(),
                                                        restoration_normal_iterations(post), threads,
                                                        walls.empty() ? nullptr : &walls);
    }

    // Capped, every vertex stays inside the box: volume restoration moves vertices near a wall along normals that may
    // point through it. Before the collapse guard, which reverts a component this leaves with a flat triangle.
    if (capped && post.smoothing_iterations > 0)
        stats.set_count("container_clamped_vertices",
                        static_cast<double>(clamp_into_box(mesh, *container.mesh_aabb_min, *container.mesh_aabb_max)));

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

    // The open mesh box: the surface is cut there like splashsurf's.
    if (mesh_box && !capped) {
        StageTimer timer(&stats, "container");
        stats.set_count("container_removed_triangles", static_cast<double>(cut_open_at_box(
                                                           mesh, *container.mesh_aabb_min, *container.mesh_aabb_max, container.mesh_aabb_clamp_verts)));
    }

    if (mesh_box && mesh.num_triangles() == 0 && reconstruction.grid.size() > 0)
        stats.warnings.push_back("the fluid's surface lies entirely outside the mesh box (mesh_aabb_min/max): the mesh is empty");

    // Quads last: merging faces moves no vertex, so normals and attributes stay as they are.
    if (post.generate_quads) {
        StageTimer timer(&stats, "quads");
        const QuadCriteria criteria{post.quad_max_edge_diag_ratio, post.quad_max_normal_angle, post.quad_max_interior_angle};
        stats.set_count("quads", static_cast<double>(merge_triangles_into_quads(mesh, criteria, threads)));
    }

    // The last line of defence for the host application (post/vertex_guard.h).
    const std::size_t clamped = keep_vertices_near_particles(mesh, reconstruction.grid, surface.compact_support() + 2.0 * surface.cube_edge(), threads);
    if (clamped > 0)
        stats.warnings.push_back("internal: " + std::to_string(clamped) + " vertices were outside the particles' reach and were clamped");
    stats.set_count("vertices", static_cast<double>(mesh.num_vertices()));
    stats.set_count("triangles", static_cast<double>(mesh.num_triangles()));
    result.mesh = std::move(mesh);
    return result;
}

}  // namespace meniscus
