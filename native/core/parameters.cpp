#include "parameters.h"

#include <cmath>
#include <limits>
#include <type_traits>

#include "base/decimal.h"
#include "base/errors.h"

namespace meniscus {

namespace {

constexpr double kUnbounded = std::numeric_limits<double>::infinity();

// One entry of the schema, written as a chain: Spec::real("cube_size", ...).label(...).range(...)...
class Spec {
public:
    template <class Group, class Field>
    static Spec make(ParameterType type, const char* name, Group Parameters::*group, Field Group::*field) {
        Spec s;
        s.spec_.name = name;
        s.spec_.type = type;
        s.spec_.get = [group, field](const Parameters& p) { return static_cast<double>(p.*group.*field); };
        s.spec_.set = [group, field](Parameters& p, double value) {
            if constexpr (std::is_same_v<Field, bool>)
                p.*group.*field = value != 0.0;
            else
                p.*group.*field = static_cast<Field>(value);
        };
        return s;
    }
    template <class Group>
    static Spec flag(const char* name, bool Group::*field, Group Parameters::*group) {
        return make(ParameterType::flag, name, group, field).cli_style(CliStyle::on_off);
    }
    template <class Group>
    static Spec count(const char* name, int Group::*field, Group Parameters::*group) {
        return make(ParameterType::count, name, group, field).range(0, 1000000);
    }
    template <class Group>
    static Spec real(const char* name, double Group::*field, Group Parameters::*group) {
        return make(ParameterType::real, name, group, field);
    }
    template <class Group>
    static Spec vector(const char* name, std::optional<Vector3> Group::*field, Group Parameters::*group) {
        Spec s;
        s.spec_.name = name;
        s.spec_.type = ParameterType::vector3;
        s.spec_.get = [](const Parameters&) { return 0.0; };
        s.spec_.set = [](Parameters&, double) {};
        s.spec_.get_vector = [group, field](const Parameters& p) { return p.*group.*field; };
        s.spec_.set_vector = [group, field](Parameters& p, const std::optional<Vector3>& value) { p.*group.*field = value; };
        return s;
    }

    Spec& group(const char* g) { spec_.group = g; return *this; }
    Spec& label(const char* l) { spec_.label = l; return *this; }
    Spec& cli(const char* c) { spec_.cli = c; return *this; }
    Spec& cli_style(CliStyle s) { spec_.cli_style = s; return *this; }
    Spec& unit(const char* u) { spec_.unit = u; return *this; }
    Spec& help(const char* h) { spec_.help = h; return *this; }
    Spec& range(double lo, double hi, bool lo_open = false, bool hi_open = false) {
        spec_.minimum = lo;
        spec_.maximum = hi;
        spec_.minimum_open = lo_open;
        spec_.maximum_open = hi_open;
        spec_.soft_minimum = lo;
        spec_.soft_maximum = std::isinf(hi) ? lo : hi;
        return *this;
    }
    Spec& positive() { return range(0.0, kUnbounded, true); }
    Spec& soft(double lo, double hi) { spec_.soft_minimum = lo; spec_.soft_maximum = hi; return *this; }
    Spec& automatic(double value, const char* word, double suggested) {
        spec_.automatic = value;
        spec_.automatic_word = word;
        spec_.suggested = suggested;
        return *this;
    }
    Spec& required(double suggested) {
        spec_.required = true;
        suggested_ = suggested;
        return *this;
    }
    Spec& depends_on(const char* name) { spec_.depends_on = name; return *this; }
    ParameterSpec done() {
        if (!spec_.automatic && !spec_.is_vector()) spec_.suggested = spec_.required ? suggested_ : spec_.default_value();
        if (spec_.type == ParameterType::flag) spec_.soft_maximum = 1.0;
        return std::move(spec_);
    }

private:
    ParameterSpec spec_;
    double suggested_ = 0.0;
};

std::vector<ParameterSpec> make_schema() {
    using R = ReconstructionParams;
    using P = PostprocessParams;
    using E = ExecutionOptions;
    constexpr auto surface = &Parameters::reconstruction;
    constexpr auto post = &Parameters::postprocess;
    constexpr auto execution = &Parameters::execution;
    std::vector<ParameterSpec> s;

    // ---- surface (Sec. 3.1) -----------------------------------------------------------------------------------
    s.push_back(Spec::real("particle_radius", &R::particle_radius, surface).group("surface").label("Particle Radius")
                    .cli("-r,--particle-radius").unit("scene units").positive().soft(1e-4, 1.0).required(0.025)
                    .help("Radius of one particle; the other lengths are multiples of it").done());
    s.push_back(Spec::real("smoothing_length", &R::smoothing_length, surface).group("surface").label("Smoothing Length")
                    .cli("-l,--smoothing-length").unit("particle radii").positive().soft(1.0, 4.0)
                    .help("How far each particle's influence reaches (the kernel support is 2 x this x radius). Larger: "
                          "blobbier, fewer holes; smaller: more detail, more holes").done());
    s.push_back(Spec::real("cube_size", &R::cube_size, surface).group("surface").label("Cube Size")
                    .cli("-c,--cube-size").unit("particle radii").positive().soft(0.2, 3.0)
                    .help("Edge of the marching-cubes cells. Smaller gives a finer surface and more triangles (halving "
                          "it means about four times as many)").done());
    s.push_back(Spec::real("iso_threshold", &R::iso_threshold, surface).group("surface").label("Iso Threshold")
                    .cli("-t,--surface-threshold").positive().soft(0.1, 1.5)
                    .help("Where the surface lies, as a fraction of the fluid's density: higher pulls it in (thinner "
                          "splashes), lower pushes it out (fuller, more merged drops)").done());
    s.push_back(Spec::count("fill_interior", &R::fill_interior, surface).group("surface").label("Fill Interior")
                    .cli("--fill-interior").range(0, 1).automatic(-1.0, "auto", 1.0)
                    .help("Make solid water from particles kept only in a band under the liquid's surface (Mantaflow's "
                          "FLIP particles): what the band encloses, bounded by the domain's walls and obstacles, is "
                          "filled with particles. 1: on (the particles must come with their fluid domain), 0: off; "
                          "automatic: on when they come from a narrow band (Mantaflow's cache)").done());
    s.push_back(Spec::count("fluid_surface", &R::fluid_surface, surface).group("surface").label("Fluid Surface")
                    .cli("--fluid-surface").range(0, 1).automatic(-1.0, "auto", 1.0)
                    .help("Which surface a grid solver's liquid gets. 1: the one Mantaflow meshes itself (its particle "
                          "level set on the domain's grid refined by the Mesh panel's Upres Factor, joined with the "
                          "liquid the particles enclose; the particles must come with their fluid domain): the volume "
                          "of Blender's own liquid mesh. 0: the particles' SPH surface, smoothed (Fill Interior fills "
                          "a narrow band). Automatic: 1 when the particles come from a narrow band (Mantaflow's "
                          "cache)").done());

    // ---- mesh (Sec. 3.3) --------------------------------------------------------------------------------------
    s.push_back(Spec::flag("decimate_barnacles", &P::decimate_barnacles, post).group("mesh").label("Remove Barnacles")
                    .cli("--decimate-barnacles")
                    .help("Collapse the small bumps (barnacles) that marching cubes leaves on flat water").done());
    s.push_back(Spec::flag("mesh_cleanup", &P::mesh_cleanup, post).group("mesh").label("Mesh Cleanup")
                    .cli("--mesh-cleanup")
                    .help("Merge the tiny, thin triangles that marching cubes makes: fewer triangles, better shading")
                    .done());
    s.push_back(Spec::real("mesh_cleanup_snap_distance", &P::mesh_cleanup_snap_distance, post).group("mesh")
                    .label("Snap Distance").cli("--mesh-cleanup-snap-dist").unit("cube sizes").range(0.0, 1.0)
                    .automatic(-1.0, "all", 0.5).depends_on("mesh_cleanup")
                    .help("Clean up only vertices this close to a grid point (all vertices when automatic)").done());

    s.push_back(Spec::count("stray_min_particles", &P::stray_min_particles, post).group("mesh")
                    .label("Stray Min Particles").cli("--stray-min-particles").soft(0, 100)
                    .help("Remove stray blobs: pieces of the surface made by fewer particles than this (0: keep all). A "
                          "droplet keeps its particle count from frame to frame, so it stays or goes for the whole "
                          "sequence").done());
    s.push_back(Spec::real("stray_min_volume", &P::stray_min_volume, post).group("mesh").label("Stray Min Volume")
                    .cli("--stray-min-volume").unit("particle volumes").range(0.0, kUnbounded).soft(0.0, 100.0)
                    .help("Remove stray blobs: pieces of the surface enclosing less than this many particle volumes "
                          "(4/3 pi r^3 each; 0: keep all)").done());

    // ---- smoothing (Sec. 3.2, Eq. 3-9) -------------------------------------------------------------------------
    s.push_back(Spec::count("smoothing_iterations", &P::smoothing_iterations, post).group("smoothing")
                    .label("Smoothing Iterations").cli("--mesh-smoothing-iters").soft(0, 100)
                    .help("Smoothing on or off (0). With Smoothing Reach 0, how many times the surface is smoothed (the "
                          "paper's iterations: they remove the bumps of individual particles, reaching less far the finer "
                          "the cubes)")
                    .done());
    s.push_back(Spec::real("smoothing_strength", &P::smoothing_strength, post).group("smoothing")
                    .label("Smoothing Strength").cli("--mesh-smoothing-strength,--mesh-smoothing-beta")
                    .range(0.0, 1.0, true).depends_on("smoothing_iterations,!smoothing_reach")
                    .help("How far each smoothing iteration moves a vertex towards its neighbours (1: all the way; with "
                          "Smoothing Reach 0 only)").done());
    s.push_back(Spec::real("smoothing_reach", &P::smoothing_reach, post).group("smoothing").label("Smoothing Reach")
                    .cli("--mesh-smoothing-reach").unit("particle radii").range(0.0, 64.0).soft(0.0, 10.0)
                    .depends_on("smoothing_iterations")
                    .help("How far smoothing reaches: a heat flow that removes the particles' bumps alike at every cube "
                          "size up to 0.5 (growing with the cube above it, as coarse cubes need) while tubes, sheets and "
                          "drops keep their volume where they are (4.28: as far as 64 iterations at cube size 0.5). 0: the "
                          "paper's iterations instead, less than half the cost, whose reach shrinks with the cube and "
                          "whose lost volume is given back per piece").done());
    s.push_back(Spec::flag("smoothing_weights", &P::smoothing_weights, post).group("smoothing").label("Keep Splashes")
                    .cli("--mesh-smoothing-weights").depends_on("smoothing_iterations")
                    .help("Smooth flat water fully but thin splashes and drops less, so they keep their shape (feature "
                          "weights from the particle neighbourhood; off: uniform smoothing)").done());
    s.push_back(Spec::real("weights_normalization", &P::weights_normalization, post).group("smoothing")
                    .label("Neighbour Count").cli("--mesh-smoothing-weights-normalization").positive().soft(1.0, 20.0)
                    .automatic(0.0, "auto", 5.0).depends_on("smoothing_weights")
                    .help("Distance-weighted neighbour count expected at a flat surface: places with fewer neighbours "
                          "are treated as splash and smoothed less. Automatic: measured per frame (about 5 for SPH data "
                          "at rest density; splashsurf's 13 counts differently and does not apply)").done());
    s.push_back(Spec::flag("weights_smoothstep", &P::weights_smoothstep, post).group("smoothing")
                    .label("Sharpen Weights").cli("--mesh-smoothing-weights-smoothstep").depends_on("smoothing_weights")
                    .help("Push the feature weights towards 0 and 1 (the paper's smoothstep, Eq. 9)").done());
    s.push_back(Spec::flag("volume_restoration", &P::volume_restoration, post).group("smoothing").label("Keep Volume")
                    .cli("--mesh-smoothing-volume-restoration").depends_on("smoothing_iterations")
                    .help("Give each piece of water the volume smoothing took: with the reach a final correction of "
                          "about a hundredth of a particle radius, with the iterations a push back out along the normals")
                    .done());

    // ---- normals (Sec. 3.4) -----------------------------------------------------------------------------------
    s.push_back(Spec::flag("normals", &P::normals, post).group("normals").label("Normals").cli("--normals")
                    .help("Compute vertex normals (area-weighted, then smoothed) for smooth shading").done());
    s.push_back(Spec::count("normal_smoothing_iterations", &P::normal_smoothing_iterations, post).group("normals")
                    .label("Normal Smoothing").cli("--normals-smoothing-iters").soft(0, 50).depends_on("normals")
                    .help("How many times the normals are averaged with their neighbours: softer shading, fewer visible "
                          "facets (0: off)").done());
    s.push_back(Spec::flag("sph_normals", &P::sph_normals, post).group("normals").label("Particle Normals")
                    .cli("--sph-normals").depends_on("normals")
                    .help("Take normals from the particles' density gradient instead of the mesh: smoother on coarse "
                          "meshes, slower").done());

    // ---- output -----------------------------------------------------------------------------------------------
    s.push_back(Spec::flag("output_weights", &P::output_weights, post).group("output").label("Weights Attribute")
                    .cli("--output-smoothing-weights")
                    .help("Store the feature weights as the vertex attribute 'weights' (0 in splashes, 1 in calm "
                          "water), e.g. to shade foam").done());

    s.push_back(Spec::flag("generate_quads", &P::generate_quads, post).group("output").label("Quads")
                    .cli("--generate-quads")
                    .help("Merge pairs of nearly coplanar triangles into nearly rectangular quads, for subdividing and "
                          "remeshing").done());
    s.push_back(Spec::real("quad_max_edge_diag_ratio", &P::quad_max_edge_diag_ratio, post).group("output")
                    .label("Quad Edge/Diagonal Ratio").cli("--quad-max-edge-diag-ratio").range(1.0, kUnbounded)
                    .soft(1.0, 3.0).depends_on("generate_quads")
                    .help("Largest ratio of a quad's edge to its diagonal (the inverse is the smallest): lower makes "
                          "squarer quads and fewer of them").done());
    s.push_back(Spec::real("quad_max_normal_angle", &P::quad_max_normal_angle, post).group("output")
                    .label("Quad Max Fold").cli("--quad-max-normal-angle").unit("degrees").range(0.0, 180.0)
                    .depends_on("generate_quads")
                    .help("Largest angle between the normals of two triangles merged into a quad").done());
    s.push_back(Spec::real("quad_max_interior_angle", &P::quad_max_interior_angle, post).group("output")
                    .label("Quad Max Corner").cli("--quad-max-interior-angle").unit("degrees").range(0.0, 180.0)
                    .depends_on("generate_quads")
                    .help("Largest angle at any corner of a quad").done());

    // ---- container (splashsurf's boxes) ------------------------------------------------------------------------
    using C = ContainerParams;
    constexpr auto container = &Parameters::container;
    s.push_back(Spec::vector("particle_aabb_min", &C::particle_aabb_min, container).group("container")
                    .label("Particle Box Min").cli("--particle-aabb-min").unit("scene units")
                    .help("Lower corner of the box of particles to keep: particles outside it are dropped before the "
                          "reconstruction (with a count in the stats)").done());
    s.push_back(Spec::vector("particle_aabb_max", &C::particle_aabb_max, container).group("container")
                    .label("Particle Box Max").cli("--particle-aabb-max").unit("scene units")
                    .help("Upper corner of the box of particles to keep").done());
    s.push_back(Spec::vector("mesh_aabb_min", &C::mesh_aabb_min, container).group("container").label("Container Min")
                    .cli("--mesh-aabb-min").unit("scene units")
                    .help("Lower corner of the container: the surface is cut at its walls, so that fluid resting on a "
                          "floor or against a wall meets it flat and flush").done());
    s.push_back(Spec::vector("mesh_aabb_max", &C::mesh_aabb_max, container).group("container").label("Container Max")
                    .cli("--mesh-aabb-max").unit("scene units").help("Upper corner of the container").done());
    s.push_back(Spec::flag("mesh_aabb_cap", &C::mesh_aabb_cap, container).group("container").label("Closed At Walls")
                    .cli("--mesh-aabb-cap")
                    .help("Close the surface where the container cuts it, with flat faces on the walls (renderers need a "
                          "closed surface for refraction and absorption); off: an open cut").done());
    s.push_back(Spec::flag("mesh_aabb_clamp_verts", &C::mesh_aabb_clamp_verts, container).group("container")
                    .label("Clamp To Walls").cli("--mesh-aabb-clamp-verts")
                    .help("With an open cut: move the vertices outside the container onto its walls (splashsurf's "
                          "clamping; closed surfaces always end exactly on the walls)").done());

    // ---- execution --------------------------------------------------------------------------------------------
    s.push_back(Spec::count("threads", &E::threads, execution).group("execution").label("Threads").cli("-n,--threads")
                    .range(1, 4096).soft(1, 64).automatic(0.0, "all", 4.0)
                    .help("CPU threads the reconstruction uses (automatic: the cores other programs leave free as each frame starts)").done());
    s.push_back(Spec::real("memory_budget", &E::memory_budget, execution).group("execution").label("Memory Limit")
                    .cli("--memory-budget").unit("GiB").positive().soft(0.5, 256.0).automatic(0.0, "auto", 8.0)
                    .help("Refuse a frame that would need more memory than this, with the estimate, instead of "
                          "exhausting the machine (automatic: 75 % of the installed memory)").done());
    s.push_back(Spec::flag("skip_invalid", &E::skip_invalid, execution).group("execution").label("Skip Invalid Particles")
                    .cli("--skip-invalid")
                    .help("Drop particles with NaN or infinite coordinates (with a warning) instead of refusing the "
                          "frame").done());
    return s;
}

bool is_whole(double value) { return std::floor(value) == value; }

}  // namespace

std::size_t ExecutionOptions::memory_budget_bytes() const {
    return memory_budget > 0.0 ? static_cast<std::size_t>(memory_budget * 1024.0 * 1024.0 * 1024.0) : 0;
}

const std::vector<ParameterSpec>& parameter_schema() {
    static const std::vector<ParameterSpec> schema = make_schema();
    return schema;
}

const ParameterSpec& find_parameter(const std::string& name) {
    std::string names;
    for (const auto& spec : parameter_schema()) {
        if (spec.name == name) return spec;
        names += (names.empty() ? "" : ", ") + spec.name;
    }
    throw InputError("no parameter '" + name + "' (the parameters are: " + names + ")");
}

std::string ParameterSpec::allowed() const {
    if (type == ParameterType::flag) return "on or off";
    if (type == ParameterType::vector3) return "three numbers (x y z)";
    std::string lower, upper;
    if (!std::isinf(minimum)) lower = (minimum_open ? "greater than " : "at least ") + format_number(minimum);
    if (!std::isinf(maximum) && maximum < 1000000) upper = (maximum_open ? "less than " : "at most ") + format_number(maximum);
    std::string text = type == ParameterType::count ? "a whole number" : "a number";
    if (!lower.empty()) text += " " + lower;
    if (!upper.empty()) text += (lower.empty() ? " " : " and ") + upper;
    if (automatic) text += ", or " + format_number(*automatic) + " for automatic (" + automatic_word + ")";
    return text;
}

std::optional<std::string> ParameterSpec::problem(double value) const {
    const std::string got = ", got " + format_number(value);
    if (automatic && value == *automatic) return std::nullopt;
    if (std::isnan(value) || std::isinf(value)) return "must be " + allowed() + got;
    if (type == ParameterType::flag) {
        if (value != 0.0 && value != 1.0) return "must be on or off" + got;
        return std::nullopt;
    }
    const bool below = minimum_open ? value <= minimum : value < minimum;
    const bool above = maximum_open ? value >= maximum : value > maximum;
    if (below || above || (type == ParameterType::count && !is_whole(value))) return "must be " + allowed() + got;
    return std::nullopt;
}

std::optional<std::string> ParameterSpec::problem(const std::optional<Vector3>& value) const {
    if (!value) return std::nullopt;
    for (double x : *value)
        if (!std::isfinite(x)) return "must be three finite numbers, got " + format_number(x) + " in it";
    return std::nullopt;
}

namespace {

// Both corners of a box or neither, and the lower one below the upper one in every coordinate.
void validate_box(const std::optional<Vector3>& lower, const std::optional<Vector3>& upper, const char* lower_name, const char* upper_name) {
    if (lower.has_value() != upper.has_value())
        throw InputError(std::string(lower ? lower_name : upper_name) + " is given without " + (lower ? upper_name : lower_name) +
                         ": a box needs both corners");
    if (!lower) return;
    for (int k = 0; k < 3; ++k)
        if (!((*lower)[k] < (*upper)[k]))
            throw InputError(std::string(lower_name) + " must be below " + upper_name + " in every coordinate, got " +
                             format_number((*lower)[k]) + " and " + format_number((*upper)[k]) + " in " + "xyz"[k]);
}

}  // namespace

void validate(const Parameters& parameters) {
    for (const auto& spec : parameter_schema()) {
        const auto problem = spec.is_vector() ? spec.problem(spec.get_vector(parameters)) : spec.problem(spec.get(parameters));
        if (problem) throw InputError(spec.name + " " + *problem);
    }
    const ContainerParams& c = parameters.container;
    validate_box(c.particle_aabb_min, c.particle_aabb_max, "particle_aabb_min", "particle_aabb_max");
    validate_box(c.mesh_aabb_min, c.mesh_aabb_max, "mesh_aabb_min", "mesh_aabb_max");
}

void validate(const ReconstructionParams& reconstruction) {
    Parameters parameters;
    parameters.reconstruction = reconstruction;
    validate(parameters);
}

namespace {

// "1.5e-04" -> "0.00015", "2.5e+06" -> "2500000": people read plain decimals better while they stay short.
std::string without_exponent(const std::string& text) {
    const std::size_t e = text.find_first_of("eE");
    if (e == std::string::npos) return text;
    const int exponent = std::stoi(text.substr(e + 1));
    if (exponent < -6 || exponent > 15) return text;
    std::string mantissa = text.substr(0, e);
    const bool negative = !mantissa.empty() && mantissa[0] == '-';
    if (negative) mantissa.erase(0, 1);
    const std::size_t point = mantissa.find('.');
    std::string digits = mantissa;
    int integer_digits = static_cast<int>(point == std::string::npos ? mantissa.size() : point);
    if (point != std::string::npos) digits.erase(point, 1);
    integer_digits += exponent;
    std::string out;
    if (integer_digits <= 0) {
        out = "0." + std::string(static_cast<std::size_t>(-integer_digits), '0') + digits;
    } else if (integer_digits >= static_cast<int>(digits.size())) {
        out = digits + std::string(static_cast<std::size_t>(integer_digits) - digits.size(), '0');
    } else {
        out = digits.substr(0, static_cast<std::size_t>(integer_digits)) + "." + digits.substr(static_cast<std::size_t>(integer_digits));
    }
    return negative ? "-" + out : out;
}

}  // namespace

std::string format_number(double value) {
    if (std::isnan(value)) return "nan";
    if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
    if (is_whole(value) && std::fabs(value) < 1e15) return std::to_string(static_cast<long long>(value));
    char text[40];
    // A value that is a float (0.025 typed in a UI arrives as 0.0250000004) reads best as that float's shortest text.
    const float as_float = static_cast<float>(value);
    if (static_cast<double>(as_float) == value) return without_exponent(std::string(text, format_decimal(text, as_float)));
    return without_exponent(std::string(text, format_decimal(text, value)));
}

}  // namespace meniscus
