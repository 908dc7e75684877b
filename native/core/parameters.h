// The parameter schema: every pipeline parameter once. The structs below hold each stage's parameters with their
// defaults; parameter_schema() (parameters.cpp) gives each one its name, range, unit, help text and spellings. From
// them the core validates, the Python binding converts keyword arguments, the command line makes its flags, the
// Python API builds reconstruct()'s signature and docstring, and the Blender add-on makes its properties and
// tooltips, so every interface has the same parameters with the same defaults: the paper's pipeline.
//
// Adding a parameter: a field (with its default) in the struct of the stage that uses it, an entry in
// parameter_schema(), and the stage's use of it. Nothing else.
//
// Names and conventions follow splashsurf: lengths given "relative" are multiples of the particle radius.
#pragma once
#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace meniscus {

struct ReconstructionParams {
    double particle_radius = 0.0;  // r, absolute (scene units); required
    double smoothing_length = 2.0;  // l, multiple of r; kernel compact support H = 2 * l * r
    double cube_size = 0.5;         // c, marching-cubes cube edge as a multiple of r
    double iso_threshold = 0.6;     // t, inside where the colour field exceeds t
    int fill_interior = -1;         // narrow-band fill (sph/interior_fill.h): 1 on, 0 off, -1 when a narrow band's domain comes with the particles
    int fluid_surface = -1;         // 1 Mantaflow's own level set (surface/particle_level_set.h), 0 the particles' SPH surface, -1 the level set for a narrow band's domain

    double compact_support() const { return 2.0 * smoothing_length * particle_radius; }
    double cube_edge() const { return cube_size * particle_radius; }
};

struct PostprocessParams {
    bool mesh_cleanup = false;                 // collapse one-ring neighbours sharing the nearest grid point
    double mesh_cleanup_snap_distance = -1.0;  // only vertices this close to their grid point (multiple of c); < 0: all
    bool decimate_barnacles = true;            // remove single-/double-vertex MC configurations (Sec. 3.3)
    int stray_min_particles = 0;               // pieces made by fewer particles are removed; 0: off
    double stray_min_volume = 0.0;             // pieces enclosing less (in particle volumes) are removed; 0: off
    int smoothing_iterations = 25;             // weighted Laplacian iterations (Eq. 3-5)
    double smoothing_strength = 1.0;           // explicit step scale (the paper's beta)
    double smoothing_reach = 4.28;             // heat flow of this reach in r (post/heat_smoothing.h, kMeasuredReach); 0: the iterations
    bool smoothing_weights = true;             // feature weights (Sec. 3.2); off: uniform smoothing
    double weights_normalization = 0.0;        // N_HS; 0: automatic
    bool weights_smoothstep = true;            // Eq. 9
    bool volume_restoration = true;            // give each component back the volume smoothing took (volume.h)
    bool output_weights = false;               // add the weights as vertex attribute "weights"
    bool normals = true;                       // area-weighted vertex normals
    int normal_smoothing_iterations = 10;      // Eq. 12
    bool sph_normals = false;                  // normals from the colour-field gradient instead
    bool generate_quads = false;               // merge triangle pairs into quads (post/quads.h)
    double quad_max_edge_diag_ratio = 1.75;    // each quad edge / diagonal within [1/this, this]
    double quad_max_normal_angle = 10.0;       // degrees between the two triangles' normals
    double quad_max_interior_angle = 135.0;    // degrees, at each corner of the quad
};

struct ExecutionOptions {
    int threads = 0;                   // 0: all available
    double memory_budget = 0.0;        // GiB; 0: 75 % of the machine's physical memory
    bool skip_invalid = false;         // drop NaN/Inf particles (with a warning) instead of failing

    std::size_t memory_budget_bytes() const;  // 0 when automatic
};

using Vector3 = std::array<double, 3>;

// The fluid's container (splashsurf's boxes). Unset boxes: no container.
struct ContainerParams {
    std::optional<Vector3> particle_aabb_min, particle_aabb_max;  // particles outside are dropped before anything else
    std::optional<Vector3> mesh_aabb_min, mesh_aabb_max;          // the surface is cut at this box
    bool mesh_aabb_cap = true;           // the cut closed by flat faces on the walls; off: an open cut
    bool mesh_aabb_clamp_verts = false;  // with an open cut: vertices outside moved onto the box's faces
};

// Every parameter of one pipeline run, at its default unless set.
struct Parameters {
    ReconstructionParams reconstruction;
    PostprocessParams postprocess;
    ExecutionOptions execution;
    ContainerParams container;
};

// flag, count, real: one number (get / set); vector3: three numbers or unset (get_vector / set_vector).
enum class ParameterType { flag, count, real, vector3 };

// How the command line spells a value: a number (or the automatic word), or on|off (a bare switch means on).
enum class CliStyle { value, on_off };

struct ParameterSpec {
    std::string name;         // Python keyword and Blender property: "smoothing_iterations"
    std::string group;        // section in help texts and panels: surface, smoothing, mesh, normals, output, execution
    ParameterType type = ParameterType::real;
    std::string label;        // as the Blender add-on shows it: "Smoothing Iterations"
    std::string cli;          // command-line names (CLI11 syntax): "--mesh-smoothing-iters"
    CliStyle cli_style = CliStyle::value;
    std::string unit;         // "scene units", "particle radii", "GiB", "" for plain numbers
    std::string help;         // what it does, in the user's terms
    double minimum = 0.0, maximum = 0.0;  // allowed range (ignored for flags)
    bool minimum_open = false, maximum_open = false;  // an open end excludes its bound
    std::optional<double> automatic;  // a value outside the range that means "choose automatically"
    std::string automatic_word;       // its spelling on the command line and in help texts: "auto"
    double suggested = 0.0;           // a reasonable value to offer where the default is automatic (UIs)
    double soft_minimum = 0.0, soft_maximum = 0.0;  // the usual range, for sliders
    bool required = false;            // no default: the caller must give it
    // When this one matters: comma-separated conditions, all of which must hold; "name" a flag or number that must be
    // on (non-zero), "!name" one that must be off (zero): "smoothing_iterations,!smoothing_reach".
    std::string depends_on;

    std::function<double(const Parameters&)> get;
    std::function<void(Parameters&, double)> set;
    std::function<std::optional<Vector3>(const Parameters&)> get_vector;
    std::function<void(Parameters&, const std::optional<Vector3>&)> set_vector;

    bool is_vector() const { return type == ParameterType::vector3; }
    double default_value() const { return is_vector() ? 0.0 : get(Parameters{}); }
    // What is wrong with a value ("must be greater than 0 and at most 1, got 0"), or nothing when it is allowed.
    std::optional<std::string> problem(double value) const;
    // The same for a vector: every coordinate a finite number (unset is always allowed).
    std::optional<std::string> problem(const std::optional<Vector3>& value) const;
    // The allowed values in words: "greater than 0 and at most 1", "a whole number from 0", "on or off".
    std::string allowed() const;
};

const std::vector<ParameterSpec>& parameter_schema();
// The parameter of that name; InputError listing the names when there is none.
const ParameterSpec& find_parameter(const std::string& name);

// InputError naming the first parameter whose value is not allowed (by its schema name), or a box whose corners are
// not both given or not below one another.
void validate(const Parameters& parameters);
void validate(const ReconstructionParams& parameters);

// A number as people write it: 0, 0.5, 2.5e-06, 1000 (shortest form that reads back the same).
std::string format_number(double value);

}  // namespace meniscus
