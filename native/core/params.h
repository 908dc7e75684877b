// Parameter collections of the pipeline. Names and conventions follow splashsurf so its users feel at home:
// lengths given "relative" are multiples of the particle radius.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace meniscus {

struct ReconstructionParams {
    double particle_radius = 0.0;      // r, absolute (scene units); must be > 0
    double smoothing_length = 2.0;     // l, multiple of r; kernel compact support H = 2 * l * r
    double cube_size = 0.5;            // c, marching-cubes cube edge as a multiple of r
    double iso_threshold = 0.6;        // t, inside where the colour field exceeds t

    double compact_support() const { return 2.0 * smoothing_length * particle_radius; }
    double cube_edge() const { return cube_size * particle_radius; }
};

struct PostprocessParams {
    bool mesh_cleanup = false;                // collapse one-ring neighbours sharing the nearest grid point
    double mesh_cleanup_snap_distance = -1.0;   // only vertices within this distance (multiple of the cube edge) of a grid point; < 0: all
    bool decimate_barnacles = false;          // remove single-/double-vertex MC configurations (Sec. 3.3)
    int smoothing_iterations = 0;             // weighted Laplacian iterations (Eq. 3-5)
    double smoothing_beta = 1.0;              // explicit step scale beta
    bool smoothing_weights = true;            // feature weights (Sec. 3.2); off: uniform smoothing
    double weights_normalization = 0.0;       // N_HS; <= 0 means automatic
    bool weights_smoothstep = true;           // Eq. 9
    bool volume_restoration = true;           // give each component back the volume smoothing took (volume.h)
    bool output_weights = false;              // add the weights as vertex attribute "weights"
    bool normals = true;                      // area-weighted vertex normals
    int normal_smoothing_iterations = 0;      // Eq. 12
    bool sph_normals = false;                 // normals from the colour-field gradient instead
};

struct ExecutionOptions {
    int threads = 0;                          // 0: all available
    std::size_t memory_budget_bytes = 0;      // 0: a fraction of the machine's physical memory
    bool skip_invalid = false;                // drop NaN/Inf particles (with a warning) instead of failing
};

}  // namespace meniscus
