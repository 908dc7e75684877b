// Smoothness at a physical scale (issue 12) and per-component volumes and centroids, for the quality report
// (assess_quality with a scale, `meniscus inspect --particle-radius`) and the benchmarks (bench/smoothing_scale.py).
//
// hfL (the definition): the mean distance between a mesh and its own Taubin low-pass (uniform umbrella,
// lambda 0.5 / mu -0.53) with round(1.36 (L / e)^2) pass pairs, e the RAW mesh's mean edge length, L a length (2 r);
// the same passes for the raw and the smoothed mesh, reported as the ratio smoothed / raw. A lambda|mu pair has its
// passband edge at a fixed multiple of the edge length; more passes only sharpen the stop band, so this cutoff sits
// at a wavelength ~ sqrt(e L): finer for finer cubes. The heat variant below removes that
// dependence: the mean distance to the mesh's own low-pass 2 H(t) - H(2 t), H(t) the heat flow of time t = L^2 / 4 (a
// Chebyshev polynomial of the umbrella operator, heat_smoothing.h, N = (L / e_rms)^2 for the mesh's own RMS edge):
// the same physical filter at every cube size, and flat to second order at low frequencies like Taubin's lambda|mu,
// so that a tube's or a drop's shrinkage under the heat flow does not count as bumps.
#pragma once
#include <vector>

#include "mesh/mesh.h"

namespace meniscus {

struct MeshAdjacency;

// Mean distance between the mesh and its Taubin low-pass of `passes` lambda|mu pairs, over vertices with neighbours.
double taubin_distance(const TriMesh& mesh, const MeshAdjacency& adjacency, int passes, int threads);
// The Taubin pass count of the hfL: round(1.36 (length / raw_mean_edge)^2).
int hfl_passes(double length, double raw_mean_edge);
// Mean distance between the mesh and its low-pass 2 H(t) - H(2 t), t = length^2 / 4 (unweighted umbrella, Chebyshev).
double heat_distance(const TriMesh& mesh, const MeshAdjacency& adjacency, double length, int threads);
// Mean edge length over the mesh's edges (each edge once; deterministic sum).
double mean_edge_length(const TriMesh& mesh, const MeshAdjacency& adjacency, int threads);

struct ComponentSummary {
    std::vector<double> volume;    // signed enclosed volume per component with triangles (in triangle order of first use)
    std::vector<double> centroid;  // 3 per component: centroid of the enclosed solid (vertex mean if degenerate)
};
ComponentSummary component_summary(const TriMesh& mesh);

}  // namespace meniscus
