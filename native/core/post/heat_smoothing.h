// Smoothing of a physical reach that holds volume where it is (issue 12; beyond the paper's Eq. 5).
//
// The paper's explicit weighted Laplacian moves a vertex a fraction of an edge per iteration, so a fixed iteration
// count reaches less far the finer the cubes (and further the coarser). Here the smoothing is a heat flow of a fixed
// physical time: the weighted umbrella operator Y = I + W (mean - I) (one beta = 1 Jacobi step; eigenvalues in
// [-1, 1]) is applied as a Chebyshev expansion of exp(N (y - 1)), N = (reach / e)^2 with e the mesh's RMS edge length.
// N explicit steps are a heat time N e^2 / 4, so the heat time is reach^2 / 4 at every cube size, for about
// 4 sqrt(N x parts) operator applications instead of N (each part is its own series). Where a filter is so short
// that ceil(N) explicit steps of the same heat time are fewer than its series' terms (the parts at coarse cube sizes,
// c = 1.0: 5 steps against 7 terms; the returns' blend: 1-3 against 3-5), it runs as those steps: on the 9 shared
// frames volume and droplets stay within 1e-5, hfL within 1.1 % and the heat bumpiness within 2.1 % (both lower
// where they moved most), the sequence's flicker within 0.1 %, and c = 1.0 runs 90 operator applications on the
// mesh instead of 150.
//
// Local volume: the flow runs in parts of heat time about kPartTime r^2 (at most 5 % over). After each part the normal component of the
// part's displacement is low-passed over the surface (reach kLocalScale r) and taken back along the normals. Removing
// a particle's bump is a displacement of alternating sign and averages out; the shrinkage of a tube, sheet, crest or
// droplet is of one sign across the feature and is returned where it happened, before it can collapse anything;
// a gap's widening is returned the same way, so gaps do not close. A final per-component correction (up to 4 Newton steps
// along the smoothed normals, scaled by the feature weights: post/volume.h) brings each component's volume within
// 1e-5 of the unsmoothed one; since nothing has
// collapsed, its offsets are of the order of 0.01 r.
//
// Walls (wall_constraints.h): a vertex on a wall keeps its coordinate along the wall's normal inside the flow (the
// operator leaves that coordinate as it is) and WallConstraints::apply() runs after every step that moves vertices
// (each part of the flow, each local return, each volume-correction step), so it slides along the wall.
//
// Everything is per-vertex Jacobi arithmetic over sorted CSR rows and sums in fixed blocks: the result is the same
// bits for any thread count.
#pragma once
#include <cstdint>
#include <vector>

#include "mesh/mesh.h"
#include "post/normals.h"

namespace meniscus {

struct MeshAdjacency;
struct WallConstraints;
struct UnsmoothedSurface;

// The cube size (in r) up to which the reach stays what the user set. Above it the reach grows with the cube, as the
// paper's iterations' reach does (each moves a fraction of an edge): coarse marching cubes alias from frame to frame
// and need it. Measured on the sequence (slope flicker / pysplashsurf's): c = 1.0: 1.06 at 4 r without the growth,
// 0.92 at 5.35 r, 0.90 at 8 and 8.56 r, 0.89 at 12 r, 0.93 at 20 r (a floor: the slope of facets 1 r wide, not the
// smoothing); c = 0.75: 0.88 at 4 r, 0.73 at 6 r.
constexpr double kReferenceCube = 0.5;
// The reach of 64 explicit iterations at c = 0.5 (sqrt(64) x the RMS edge of a decimated marching-cubes mesh, 1.07
// cube edges, 1.05-1.09 on the shared frames at c = 0.25-1.0): the setting the README's figures were measured with.
constexpr double kMeasuredReach = 8.0 * 1.07 * kReferenceCube;
// Largest heat time of one part of the flow, in r^2. Within a part the flow thins a tube's necks faster than its
// bulges (a 1.5 r tube keeps ~40 % of its radius after 2.3 r^2, ~65 % after 1.25 r^2) and the return gives back the
// mean, so long parts grow beads on thin tubes: hilbert2's hfL at c = 0.5 / 0.75 / 1.0 is 0.189 / 0.148 / 0.150 with
// 2.5 r^2, 0.151 / 0.114 / 0.102 with 1.25 and 0.134 / 0.095 / 0.076 with 0.625, slope flicker the same. 1.25 doubles
// the returns of 2.5 at about the old cost (returns made cheaper with it); 0.625 would cost ~0.8 s more at 1 M.
constexpr double kPartTime = 1.25;
// Reach of the low-pass of the normal displacement that is returned after each part, in r. Smaller returns the
// particles' bumps and the pools' waves too (slope flicker at c = 0.5, reach 4.3 r: 0.060 / 0.055 / 0.054 at 6 / 9 /
// 12 r; the research measured 1 r returning every bump), larger returns a tube's shrinkage less locally (hilbert2's
// volume before the final correction: 1.011 / 1.0105 / 1.011 at c = 0.5, the same at 6-12 r).
constexpr double kLocalScale = 9.0;
// Cell of the surface aggregates (post/surface_aggregates.h) the return's low-pass runs on, in r (at least two mesh
// edges). 1, 1.5 and 2 r give the same hfL, volume and droplets to the third digit on hilbert2 and the dam breaks at
// c = 0.25 and 0.5; 1.5 r has half the aggregates of 1 r and needs a shorter blend than 2 r, and a tube 3 particles
// across still has a ring of aggregates around it. Coarser meshes take cells of two edges: at c = 1.0 (15 parts, each
// a return of ~22 applications on the mesh before) the nine frames' volume, droplets and hfL stay the same to the
// third digit (hilbert2 0.102), and the smoothing runs a third of the applications (435 -> 150).
constexpr double kAggregateCell = 1.5;
// Chebyshev tails dropped (fraction of a displacement): positions; the returned displacement. Positions at 3e-3 would
// save one application per part (13 -> 12 at c = 0.5, 7 -> 6 at c = 1.0): hfL within 4 % and the heat bumpiness 15 %
// lower on pentagonal, but up to 35 % higher on hilbert_46843 (bench/results/smoothing/table_tolerance_3e-3.json);
// 1e-2 moved the heat bumpiness by -30 % to +27 %.
constexpr double kPositionTolerance = 1e-3;
constexpr double kReturnTolerance = 1e-2;

// The reach (in r) the flow runs with at a cube size (in r): `reach` up to kReferenceCube, reach * cube / kReferenceCube
// above it.
double smoothing_reach_at(double reach, double cube_size);

// RMS edge length over the mesh's edges (deterministic sum).
double rms_edge_length(const TriMesh& mesh, const MeshAdjacency& adjacency, int threads);

// Chebyshev coefficients of exp(N (y - 1)) on [-1, 1], truncated where the tail adds up to less than `tolerance`,
// renormalised so that they sum to 1 (constants kept).
std::vector<double> heat_coefficients(double n, double tolerance);

// x <- exp(N (Y - I)) x in place, `dims` (1 or 3) floats per vertex; weights (per vertex in [0, 1]) may be empty (1
// everywhere). frozen: optional, per vertex a bit mask of coordinates (bit k: coordinate k) the operator leaves as
// they are (walls). Vertices of weight 0 or without neighbours keep their values bit for bit. Returns the number of
// operator applications. allow_explicit: ceil(N) explicit steps of the same heat time instead where they are fewer
// than the series' terms (what heat_smooth does; their response matches the heat kernel's at low frequencies).
int heat_filter(std::vector<float>& x, int dims, const MeshAdjacency& adjacency, const std::vector<float>& weights, double n,
                double tolerance, int threads, const std::vector<uint8_t>* frozen = nullptr, bool allow_explicit = false);

struct HeatSmoothingSettings {
    double reach = 0.0;             // absolute (scene units): heat time reach^2 / 4
    double particle_radius = 0.0;   // r: the unit of the part time and the local scale
    bool local_return = true;       // return the low-passed normal displacement after each part
    bool volume_correction = true;  // final per-component volume (Newton along the smoothed normals, within 1e-5)
    int normal_iterations = 10;     // smoothing of the correction's normals (Eq. 12); returned in the report
    double max_offset = 0.0;        // cap of the correction's offset (absolute; 0: 4 r)
    int parts = 0;                  // 0: automatic (heat time about part_time r^2 each); at most 10000
    double part_time = 0.0;         // in r^2; 0: kPartTime
    // Research knobs (bench/smoothing_scale.py variants; the pipeline leaves them as they are):
    double return_tolerance = 0.0;  // 0: kReturnTolerance (3e-3 / 1e-2 / 3e-2 measured: flicker 0.0597 / 0.0599 / 0.0606)
    double local_scale = 0.0;       // reach of the return's low-pass in r; 0: kLocalScale
    double aggregate_size = -1.0;   // cell of the surface aggregates the return's low-pass runs on (in r, at least two
                                    // edges); < 0: kAggregateCell; 0: on the mesh itself
    const WallConstraints* walls = nullptr;
};

struct HeatSmoothingReport {
    double edge = 0.0;                // RMS edge length used
    double iterations = 0.0;          // equivalent explicit iterations N
    int parts = 0;
    int applications = 0;             // operator applications (position flow and returned displacement)
    int coarse_applications = 0;      // applications on the aggregates (the return's low-pass)
    std::size_t aggregates = 0;       // their number
    double coarse_edge = 0.0;         // their RMS coupled distance
    SmoothedNormals normals;          // the final correction's smoothed normals (empty without it): output-ready
    std::size_t reverted_components = 0;  // collapsed components given their positions back (the whole stage only)
    // Seconds spent: flow, local return (normals, low-pass, move), final correction.
    double seconds_flow = 0.0, seconds_return = 0.0, seconds_correction = 0.0;
};

// The flow and the final correction towards the volumes of `unsmoothed` (record_unsmoothed_surface of this mesh,
// post/volume.h; only read with volume_correction). weights may be empty (plain heat flow). The pipeline runs the
// collapse guard after it, as after every smoothing.
HeatSmoothingReport heat_smooth(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& weights,
                                const HeatSmoothingSettings& settings, const UnsmoothedSurface& unsmoothed, int threads);
// The whole stage on a mesh alone: records the unsmoothed surface, smooths, then the collapse guard
// (revert_collapsed_components).
HeatSmoothingReport heat_smooth(TriMesh& mesh, const MeshAdjacency& adjacency, const std::vector<float>& weights,
                                const HeatSmoothingSettings& settings, int threads);

}  // namespace meniscus
