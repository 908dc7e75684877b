// The meniscus command line, for batch and render-farm use; flags follow splashsurf where it has them. It runs
// as the `meniscus` executable (main.cpp) and inside the Python module (`meniscus` console script of the wheel).
//   meniscus reconstruct INPUT -o OUTPUT -r R [-l L] [-c C] [-t T] [-s S -e E] [--threads N] [--stats FILE] ...
//   meniscus inspect MESH [--raw RAW] [--json FILE]
// Farm jobs (Open Job Description bundles, Dask) are written and sent by the Python console script (python/meniscus/
// farm.py, docs/farm.md); this one runs their tasks: --parameters FILE, --frames A-B, --skip-existing.
#include "cli.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "base/errors.h"
#include "io/frame_pattern.h"
#include "io/io.h"
#include "io/io_util.h"
#include "io/partial_files.h"
#include "io/provenance.h"
#include "base/memory.h"
#include "parameters_file.h"
#include "base/parallel.h"
#include "parameters.h"
#include "pipeline.h"
#include "base/platform.h"
#include "analysis/quality.h"
#include "sph/particle_box.h"
#include "surface/reconstruction.h"

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace meniscus;

namespace {

// ---- sequences ------------------------------------------------------------------------------------------------
// The frame-pattern rule (io/frame_pattern.h) shared with the Python API and the add-on: {} or #### in the input
// name stands for the frame number; fluid_{}.vtk matches fluid_7.vtk and fluid_0007.vtk alike.
struct Frame {
    long number;
    std::string digits;  // as written in the input name, reused for an output name with {}
    std::string path;
};

bool is_sequence(const std::string& pattern) { return has_frame_placeholder(pattern); }

// An output (or raw-output) name for a frame: {} takes the input's digits as written, #### pads to its width.
std::string output_path(const std::string& pattern, const Frame& frame) {
    const std::size_t at = pattern.find("{}");
    if (at != std::string::npos) return std::string(pattern).replace(at, 2, frame.digits);
    return parse_frame_pattern(pattern, std::vector<std::string>{}).path(frame.number);
}

// The frames of the input pattern; `duplicates` gets a line per frame spelled twice (which one is used and why).
std::vector<Frame> find_frames(const FramePattern& pattern, const std::string& input, std::vector<std::string>& duplicates) {
    std::error_code error;
    if (!pattern.directory.empty() && !fs::is_directory(path_from_utf8(pattern.directory), error))
        throw InputError("input pattern '" + input + "': folder '" + pattern.directory + "' does not exist");
    const FrameListing listing = list_frames(pattern);
    duplicates = listing.duplicates;
    std::vector<Frame> frames;
    for (const auto& [number, path] : listing.frames) {
        const std::string name = path_to_utf8(path_from_utf8(path).filename());
        frames.push_back({static_cast<long>(number), name.substr(pattern.prefix.size(), name.size() - pattern.prefix.size() - pattern.suffix.size()), path});
    }
    return frames;
}

// ---- progress -------------------------------------------------------------------------------------------------
class Progress {
public:
    Progress(std::size_t total, bool enabled) : total_(total), enabled_(enabled && total > 1), start_(std::chrono::steady_clock::now()) {}
    void update(std::size_t done, const std::string& label) {
        if (!enabled_) return;
        std::lock_guard<std::mutex> lock(mutex_);
        const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
        const int width = 30;
        const int filled = total_ ? static_cast<int>(width * done / total_) : width;
        const double eta = done ? elapsed / done * (total_ - done) : 0.0;
        std::fprintf(stderr, "\r[%s%s] %zu/%zu %5.1fs eta %5.1fs %-24.24s", std::string(filled, '#').c_str(),
                     std::string(width - filled, '.').c_str(), done, total_, elapsed, eta, label.c_str());
        if (done == total_) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }
    // Messages interleaved with the bar start on a fresh line.
    void message(const std::string& text) {
        std::lock_guard<std::mutex> lock(mutex_);
        std::fprintf(stderr, "%s%s\n", enabled_ ? "\n" : "", text.c_str());
        std::fflush(stderr);
    }

private:
    std::mutex mutex_;  // frames in parallel (--mt-files) report from several threads
    std::size_t total_;
    bool enabled_;
    std::chrono::steady_clock::time_point start_;
};

json stats_json(const PipelineStats& stats) {
    json out;
    out["seconds"] = json::object();
    for (const auto& s : stats.stage_seconds) out["seconds"][s.first] = s.second;
    out["seconds"]["total"] = stats.total_seconds();
    out["counts"] = json::object();
    for (const auto& c : stats.counts) out["counts"][c.first] = c.second;
    out["warnings"] = stats.warnings;
    return out;
}

json check_json(const MeshCheck& c) {
    return {{"closed", c.closed()},
            {"manifold", c.manifold()},
            {"oriented", c.oriented()},
            {"ok", c.ok()},
            {"boundary_edges", c.boundary_edges},
            {"non_manifold_edges", c.non_manifold_edges},
            {"non_manifold_vertices", c.non_manifold_vertices},
            {"inconsistent_edges", c.inconsistent_edges},
            {"degenerate_triangles", c.degenerate_triangles},
            {"non_finite_vertices", c.non_finite_vertices},
            {"summary", c.summary()}};
}

json quality_json(const MeshQuality& q) {
    json components = json::array();
    for (const auto& c : q.components) components.push_back({{"triangles", c.triangles}, {"volume", c.volume}});
    return {{"check", check_json(q.check)},
            {"vertices", q.vertices},
            {"triangles", q.triangles},
            {"volume", q.volume},
            {"area", q.area},
            {"components", components},
            {"bumpiness", q.bumpiness},
            {"mean_normal_angle_deg", q.mean_normal_angle_deg},
            {"valence_histogram", q.valence_histogram},
            {"single_vertex_configurations", q.single_vertex_configurations},
            {"double_vertex_configurations", q.double_vertex_configurations},
            {"mean_edge_length", q.mean_edge_length},
            {"scale_length", q.scale_length},
            {"hfl_passes", q.hfl_passes},
            {"hfl", q.hfl},
            {"heat_bumpiness", q.heat_bumpiness}};
}

struct ReconstructArgs {
    std::string input, output, output_dir, raw_output, stats_path;
    std::string parameters_path, save_parameters_path;  // --parameters (read before the flags) and --save-parameters
    std::string frames;                                  // --frames A-B, the same as -s A -e B (a farm task's chunk)
    bool skip_existing = false;                          // frames whose output exists are not redone
    Parameters parameters;  // the pipeline's, filled from the schema's flags
    std::optional<long> start, end;
    std::vector<std::string> attributes;
    bool check = false;
    bool quiet = false;
    bool frames_in_parallel = false;  // --mt-files
    bool threads_per_frame = true;    // --mt-particles
    bool double_precision = false;    // -d: accepted from splashsurf command lines, no effect (see add_compatibility_flags)
    bool raw_normals = false;         // --output-raw-normals: refused when on (not written)
    // splashsurf's flags that have no effect here (add_compatibility_flags): parsed into these, then unused.
    struct Ignored {
        bool subdomain_grid = true, keep_verts = false, check_debug = false;
        double rest_density = 1000.0, subdomain_cubes = 64;
    } ignored;
};

// splashsurf spells a switch --normals=on; accepted the same here, and a bare --normals means on.
bool parse_switch(const std::string& flag, const std::string& text) {
    if (text.empty() || text == "on" || text == "true" || text == "1" || text == "yes") return true;
    if (text == "off" || text == "false" || text == "0" || text == "no") return false;
    throw CLI::ValidationError(flag, "takes on or off, got '" + text + "'");
}

CLI::Option* add_switch(CLI::App& command, const std::string& names, bool& target, const std::string& help) {
    const std::string flag = names.substr(names.find("--"), names.find(',', names.find("--")) - names.find("--"));
    CLI::Option* option = command.add_option(
        names,
        [&target, flag](const CLI::results_t& results) {
            target = parse_switch(flag, results.empty() ? std::string() : results.back());
            return true;
        },
        help);
    // No default_str: CLI11 would hand it to the callback as the value of a bare switch. The default goes in the help.
    option->expected(0, 1)->type_name("[on|off]");
    option->description(help + " [default: " + (target ? "on" : "off") + "]");
    return option;
}

// The text of a schema parameter's command-line value as a number: on|off for switches, the automatic word
// (auto, all) where there is one, a number otherwise. Errors name the flag in the user's spelling.
double parse_parameter(const ParameterSpec& spec, const std::string& flag, const std::string& text) {
    double value = 0.0;
    if (spec.cli_style != CliStyle::value) return parse_switch(flag, text) ? 1.0 : 0.0;
    if (spec.automatic && text == spec.automatic_word) return *spec.automatic;
    if (!io_detail::parse_double(text, value))
        throw CLI::ValidationError(flag, "takes " + spec.allowed() + ", got '" + text + "'");
    if (auto problem = spec.problem(value)) throw CLI::ValidationError(flag, *problem);
    return value;
}

std::string cli_value_text(const ParameterSpec& spec, double value) {
    if (spec.automatic && value == *spec.automatic) return spec.automatic_word;
    if (spec.cli_style == CliStyle::on_off) return value != 0.0 ? "on" : "off";
    return format_number(value);
}

// The first long name of a schema parameter's flags: -r,--particle-radius -> --particle-radius.
std::string long_flag(const ParameterSpec& spec) {
    const std::size_t start = spec.cli.find("--");
    return spec.cli.substr(start, spec.cli.find(',', start) - start);
}

// One flag per schema parameter, with its help text, unit, allowed values and default.
void add_parameter_flags(CLI::App& command, Parameters& parameters) {
    for (const ParameterSpec& spec : parameter_schema()) {
        const std::string flag = long_flag(spec);  // the name messages use
        std::string help = spec.help;
        if (!spec.unit.empty()) help += " [" + spec.unit + "]";
        if (spec.is_vector()) {
            CLI::Option* option = command.add_option(
                spec.cli,
                [&parameters, &spec, flag](const CLI::results_t& results) {
                    Vector3 value{};
                    for (std::size_t k = 0; k < 3; ++k)
                        if (k >= results.size() || !io_detail::parse_double(results[k], value[k]))
                            throw CLI::ValidationError(flag, "takes three numbers (x y z)");
                    if (auto problem = spec.problem(std::optional<Vector3>(value))) throw CLI::ValidationError(flag, *problem);
                    spec.set_vector(parameters, value);
                    return true;
                },
                help);
            option->expected(3)->type_name("X Y Z");
            continue;
        }
        if (spec.cli_style == CliStyle::value) help += "; " + spec.allowed();
        CLI::Option* option = command.add_option(
            spec.cli,
            [&parameters, &spec, flag](const CLI::results_t& results) {
                spec.set(parameters, parse_parameter(spec, flag, results.empty() ? std::string() : results.back()));
                return true;
            },
            help);
        if (spec.cli_style == CliStyle::value) {
            option->type_name(spec.automatic ? "NUMBER|" + spec.automatic_word : "NUMBER");
        } else {
            // splashsurf's spelling --normals=on and the bare switch --normals (meaning on) both work. No
            // default_str: CLI11 would pass it as the value of a bare switch; the default goes in the help instead.
            option->expected(0, 1)->type_name("[on|off]");
            option->description(help + " [default: " + cli_value_text(spec, spec.default_value()) + "]");
            continue;
        }
        // Required, but a --parameters file may give it: checked after parsing (require_parameters).
        if (spec.required)
            option->description(help + " (required)");
        else
            option->default_str(cli_value_text(spec, spec.default_value()));
    }
}

// Writes a mesh under a temporary name in the output's folder, then renames it: a process killed mid-write (a
// preempted farm task) leaves no partial file under the output name, so an existing output is a complete one. The
// temporary name keeps the extension (it chooses the format) and holds the process id (two runs of one frame, as
// when a farm re-queues a task, do not write into each other's file). The mesh's provenance record (io/provenance.h)
// is removed before the mesh is replaced and written after it: an output never sits beside another run's record.
void write_mesh_completely(const TriMesh& mesh, const std::string& output, int threads, const std::string& provenance = "") {
    const fs::path target = path_from_utf8(output);
    const fs::path partial = path_from_utf8(hidden_partial_path(output, current_process_id()));
    std::error_code error;
    if (!target.parent_path().empty()) fs::create_directories(target.parent_path(), error);  // a farm's fresh output folder
    try {
        write_mesh(mesh, path_to_utf8(partial), threads);
    } catch (...) {
        fs::remove(partial, error);
        throw;
    }
    forget_provenance(output);
    const std::string failure = replace_file(path_to_utf8(partial), output);
    if (!failure.empty()) {
        fs::remove(partial, error);
        throw FormatError(output + ": cannot move the finished mesh into place (" + failure + ")");
    }
    if (!provenance.empty()) write_provenance(output, provenance);
}

// Runs one frame; returns the frame's JSON record. Throws on failure (the caller reports and goes on).
json run_frame(const ReconstructArgs& args, const std::string& input, const std::string& output, const std::string& raw_output,
               Progress& progress) {
    const auto start = std::chrono::steady_clock::now();
    // Before reading: a file that changes while it is read leaves a record that no longer matches it. One that cannot
    // be identified gets no record (stale when looked at again); the reader says what is wrong with it.
    std::string provenance;
    try {
        if (!output.empty()) provenance = provenance_record(args.parameters, args.attributes, input);
    } catch (const FormatError&) {
    }
    ParticleData particles = read_particles(input);
    const double read_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::vector<AttributeInput> inputs;
    for (const auto& name : args.attributes) {
        const Attribute* a = find_attribute(particles.attributes, name);
        if (!a) {
            std::string available;
            for (const auto& other : particles.attributes) available += (available.empty() ? "" : ", ") + other.name;
            throw InputError(input + ": no particle attribute '" + name + "' (the file has: " + (available.empty() ? "none" : available) + ")");
        }
        inputs.push_back({a->name, a->values.data(), a->components, a->integral});
    }
    PipelineOptions options;
    static_cast<Parameters&>(options) = args.parameters;
    options.keep_raw_mesh = !raw_output.empty();
    if (particles.fluid_domain) options.fluid_domain = &*particles.fluid_domain;  // a grid solver's cache: the narrow-band fill
    PipelineResult result;
    try {
        result = run_pipeline(PositionsView(particles.positions.data(), particles.size()), inputs, options);
    } catch (const ResourceError& e) {
        throw ResourceError(input + ": " + e.what());  // in a sequence, say which frame
    } catch (const InputError& e) {
        throw InputError(input + ": " + e.what());
    }
    result.stats.stage_seconds.insert(result.stats.stage_seconds.begin(), {"read", read_seconds});
    for (const auto& w : result.stats.warnings) progress.message(input + ": warning: " + w);

    json record;
    record["input"] = input;
    record["output"] = output;
    if (args.check) {
        const MeshCheck check = check_mesh(result.mesh);
        record["check"] = check_json(check);
        if (!check.ok()) progress.message(input + ": mesh check failed: " + check.summary());
    }
    const auto write_start = std::chrono::steady_clock::now();
    // The raw mesh first: with --skip-existing, the output's presence means the frame is complete.
    // The frame's share, as its pipeline took it (an automatic count: the cores other programs left free).
    const int taken = static_cast<int>(result.stats.count("threads"));
    const int write_threads = taken > 0 ? taken : resolve_threads(args.parameters.execution.threads);
    if (!raw_output.empty()) write_mesh_completely(result.raw_mesh, raw_output, write_threads);
    if (!output.empty()) write_mesh_completely(result.mesh, output, write_threads, provenance);
    result.stats.add_seconds("write", std::chrono::duration<double>(std::chrono::steady_clock::now() - write_start).count());
    json stats = stats_json(result.stats);
    for (auto& item : stats.items()) record[item.key()] = item.value();
    record["peak_memory_bytes"] = peak_rss_bytes();
    if (args.check && !record["check"]["ok"].get<bool>()) record["failed"] = "mesh check";
    return record;
}

// The output name of an input when -o is not given, as splashsurf names it: {input name}_surface.vtk (the
// extension of the input dropped, a .gz with it), in --output-dir or the current folder.
std::string default_output_name(const std::string& input) {
    std::string name = path_to_utf8(path_from_utf8(input).filename());
    for (const char* extension : {".gz", ""}) {
        if (*extension && !(name.size() > 3 && name.compare(name.size() - 3, 3, extension) == 0)) continue;
        if (*extension) name.erase(name.size() - 3);
        const std::size_t dot = name.rfind('.');
        if (dot != std::string::npos && dot > 0) name.erase(dot);
        break;
    }
    return name + "_surface.vtk";
}

// A path under --output-dir unless it is absolute.
std::string in_output_dir(const std::string& output_dir, const std::string& path) {
    if (output_dir.empty() || path.empty() || path_from_utf8(path).is_absolute()) return path;
    return path_to_utf8(path_from_utf8(output_dir) / path_from_utf8(path));
}

// --output-raw-mesh takes a path, or splashsurf's on/off: on writes <output>_raw<extension> beside the output.
std::string raw_output_pattern(const std::string& raw_output, const std::string& output) {
    if (raw_output.empty() || raw_output == "off") return "";
    if (raw_output != "on") return raw_output;
    const std::size_t dot = output.rfind('.');
    return dot == std::string::npos ? output + "_raw" : output.substr(0, dot) + "_raw" + output.substr(dot);
}

struct FrameJob {
    Frame frame;
    std::string output, raw_output;
};

// Flags of splashsurf's command line that choose how splashsurf computes, not what: accepted, so that its command
// lines run unchanged, and named in the help as having no effect here.
void add_compatibility_flags(CLI::App& command, ReconstructArgs& args) {
    const std::string group = "splashsurf compatibility";
    add_switch(command, "-d,--double-precision", args.double_precision,
               "No effect: double precision moves splashsurf's own vertices by at most 0.4 % of a cube and gives the same "
               "triangles")->group(group);
    ReconstructArgs::Ignored& ignored = args.ignored;
    add_switch(command, "--subdomain-grid", ignored.subdomain_grid, "No effect: Meniscus always works on a sparse grid of bricks")->group(group);
    command.add_option("--rest-density", ignored.rest_density, "No effect: the rest density cancels out of the colour field")->group(group);
    command.add_option("--subdomain-cubes", ignored.subdomain_cubes, "No effect: Meniscus's bricks are 32 cubes wide")->group(group);
    add_switch(command, "--keep-verts", ignored.keep_verts, "No effect: decimation never leaves vertices without faces")->group(group);
    add_switch(command, "--check-mesh-debug", ignored.check_debug, "No effect: the details of a failed check are in the --stats JSON")
        ->group(group);
    add_switch(command, "--output-raw-normals", args.raw_normals,
               "Not supported: only the smoothed normals are written (refused when on)")->group(group);
    command.add_flag("-v", "No effect: the summary is always printed (-q silences it)")->group(group);
}

// validate() names parameters as the schema does (mesh_aabb_min); here they are called by their flags.
void validate_in_flag_names(const Parameters& parameters) {
    try {
        validate(parameters);
    } catch (const InputError& error) {
        std::string message = error.what();
        for (const ParameterSpec& spec : parameter_schema()) {
            const std::string flag = long_flag(spec);
            for (std::size_t at = message.find(spec.name); at != std::string::npos; at = message.find(spec.name, at + flag.size())) {
                const bool whole = (at == 0 || !(std::isalnum(static_cast<unsigned char>(message[at - 1])) || message[at - 1] == '_')) &&
                                   (at + spec.name.size() == message.size() ||
                                    !(std::isalnum(static_cast<unsigned char>(message[at + spec.name.size()])) || message[at + spec.name.size()] == '_'));
                if (whole) message.replace(at, spec.name.size(), flag);
            }
        }
        throw InputError(message);
    }
}

// A parameter without default that neither a flag nor the --parameters file gave.
void require_parameters(const ReconstructArgs& args) {
    if (args.input.empty()) throw InputError("the input particle file (or pattern) is required, as the first argument or \"input\" in --parameters");
    for (const ParameterSpec& spec : parameter_schema())
        if (spec.required && spec.get(args.parameters) == spec.default_value())
            throw InputError(long_flag(spec) + " is required (or " + spec.name + " in the --parameters file)");
}

// --frames A-B (or A): a farm task's contiguous chunk of frames, the same as -s A -e B.
void apply_frame_range(ReconstructArgs& args) {
    if (args.frames.empty()) return;
    static const std::regex range(R"(\s*(-?\d+)\s*(?:-\s*(-?\d+)\s*(?::\s*1\s*)?)?)");
    std::smatch match;
    if (!std::regex_match(args.frames, match, range))
        throw InputError("--frames takes FIRST-LAST or one frame number (e.g. 1-10), got '" + args.frames + "'");
    // Checked before conversion: 99999999999999999999 is out of even a 64-bit long's range.
    for (int k = 1; k <= 2; ++k)
        if (match[k].matched && (match[k].length() > 11 || frame_number_problem(std::stoll(match[k].str()))))
            throw InputError("--frames " + args.frames + ": " + match[k].str() + " is not " + allowed_frame_numbers());
    args.start = std::stol(match[1].str());
    args.end = match[2].matched ? std::stol(match[2].str()) : *args.start;
    if (*args.end < *args.start) throw InputError("--frames " + args.frames + ": the last frame is before the first");
}

// A range is bounded before anything is made per frame: a hand-edited one would otherwise take all memory.
void check_frame_range(const ReconstructArgs& args, long first, long last) {
    if (auto problem = frame_range_problem(first, last))
        throw InputError((args.frames.empty() ? "-s/--start-index, -e/--end-index (or start, end in --parameters)"
                                              : "--frames " + args.frames) + ": " + *problem);
}

int reconstruct_command(ReconstructArgs& args, const CliHooks& hooks) {
    require_parameters(args);
    apply_frame_range(args);
    if (args.start && args.end) check_frame_range(args, *args.start, *args.end);  // --save-parameters too
    if (args.raw_normals)
        throw InputError("--output-raw-normals=on is not supported: Meniscus writes the smoothed normals only (leave it off, "
                         "or set --normals-smoothing-iters 0 for unsmoothed normals)");
    validate_in_flag_names(args.parameters);
    if (args.output.empty()) args.output = default_output_name(args.input);
    args.output = in_output_dir(args.output_dir, args.output);
    args.raw_output = in_output_dir(args.output_dir, raw_output_pattern(args.raw_output, args.output));
    if (!args.output_dir.empty()) {
        std::error_code error;
        std::filesystem::create_directories(path_from_utf8(args.output_dir), error);
        if (error) throw InputError("--output-dir '" + args.output_dir + "': cannot create the folder (" + error.message() + ")");
    }

    if (!args.save_parameters_path.empty()) {
        ParametersFile file;
        file.parameters = args.parameters;
        file.input = args.input;
        file.output = args.output;
        file.start = args.start;
        file.end = args.end;
        if (!args.attributes.empty()) file.attributes = args.attributes;
        write_parameters_file(file, args.save_parameters_path);
        if (!args.quiet) std::fprintf(stderr, "parameters written to %s (nothing reconstructed)\n", args.save_parameters_path.c_str());
        return 0;
    }

    std::vector<FrameJob> jobs;
    std::vector<std::string> duplicates;
    const bool sequence = is_sequence(args.input);
    std::optional<FramePattern> input_pattern;
    if (sequence) {
        if (!is_sequence(args.output))
            throw InputError("output '" + args.output + "' needs {} or #### for the frame number of a sequence input");
        if (!args.raw_output.empty() && !is_sequence(args.raw_output))
            throw InputError("--output-raw-mesh '" + args.raw_output + "' needs {} or #### for the frame number of a sequence input");
        input_pattern = parse_frame_pattern(args.input);
        std::vector<Frame> found = find_frames(*input_pattern, args.input, duplicates);
        const long first = args.start ? *args.start : (found.empty() ? 0 : found.front().number);
        const long last = args.end ? *args.end : (found.empty() ? -1 : found.back().number);
        check_frame_range(args, first, last);  // before a job is made per frame
        std::map<long, Frame> by_number;
        for (auto& f : found) by_number[f.number] = f;
        // Every frame of the range is attempted; one that is missing is reported like a broken one.
        for (long n = first; n <= last; ++n) {
            auto it = by_number.find(n);
            const Frame frame = it != by_number.end() ? it->second : Frame{n, std::to_string(n), ""};
            jobs.push_back({frame, output_path(args.output, frame), args.raw_output.empty() ? "" : output_path(args.raw_output, frame)});
        }
        if (jobs.empty()) throw InputError("no frames match '" + args.input + "'");
    } else {
        jobs.push_back({{0, "", args.input}, args.output, args.raw_output});
    }

    // --mt-files: frames in parallel, each on its share of the threads (one with --mt-particles=off).
    const int threads = resolve_threads(args.parameters.execution.threads);
    const int workers = args.frames_in_parallel ? std::max(1, std::min<int>(threads, static_cast<int>(jobs.size()))) : 1;
    ReconstructArgs frame_args = args;
    frame_args.parameters.execution.threads = args.threads_per_frame ? std::max(1, threads / workers) : 1;
    // One frame at a time with the automatic count: each frame takes the cores free as it starts (base/machine_load.h).
    if (workers == 1 && args.threads_per_frame && args.parameters.execution.threads == 0) frame_args.parameters.execution.threads = 0;

    Progress progress(jobs.size(), !args.quiet && is_terminal(stderr));
    for (const std::string& duplicate : duplicates) progress.message("warning: " + duplicate);
    // Runs killed mid-write (preempted farm tasks) left their temporary files in the output folders: one pass each.
    std::set<std::string> output_folders;
    for (const FrameJob& job : jobs)
        for (const std::string* output : {&job.output, &job.raw_output})
            if (!output->empty()) output_folders.insert(path_to_utf8(path_from_utf8(*output).parent_path()));
    for (const std::string& folder : output_folders) {
        const std::vector<std::string> removed = remove_abandoned_partials(folder.empty() ? "." : folder);
        if (!removed.empty())
            progress.message("removed " + std::to_string(removed.size()) + " temporary file" + (removed.size() == 1 ? "" : "s") +
                             " of killed runs in " + (folder.empty() ? "." : folder) + " (" + removed.front() +
                             (removed.size() > 1 ? ", ..." : "") + ")");
    }
    if (args.double_precision)
        progress.message("note: -d/--double-precision has no effect in Meniscus: in splashsurf itself, double precision moves "
                         "vertices by at most 0.4 % of a cube (median 0.001 %) and gives the same triangles (README, Command line)");
    std::vector<json> records(jobs.size());
    std::atomic<std::size_t> next{0}, done{0}, failed{0}, skipped{0}, redone{0};
    std::atomic<bool> interrupted{false};
    std::mutex hooks_mutex;
    auto work = [&] {
        while (!interrupted) {
            {
                std::lock_guard<std::mutex> lock(hooks_mutex);
                // Between frames: a frame once started runs to its end.
                if (hooks.interrupted && hooks.interrupted()) interrupted = true;
            }
            const std::size_t index = next++;
            if (interrupted || index >= jobs.size()) return;
            const FrameJob& job = jobs[index];
            const Frame& frame = job.frame;
            json record;
            std::error_code exists_error;
            try {
                std::string stale;  // why an existing output is not this run's (--skip-existing redoes it)
                const bool exists = args.skip_existing && !job.output.empty() && fs::exists(path_from_utf8(job.output), exists_error);
                if (exists && !frame.path.empty())
                    stale = provenance_mismatch(job.output, provenance_record(args.parameters, args.attributes, frame.path));
                if (!stale.empty()) {
                    ++redone;
                    progress.message("redoing " + job.output + ": " + stale);
                    record = run_frame(frame_args, frame.path, job.output, job.raw_output, progress);
                    record["redone"] = stale;
                    if (record.contains("failed")) ++failed;
                } else if (exists) {
                    // Outputs appear complete or not at all (write_mesh_completely), and this one was made from the
                    // same particle file with the same parameters: it is done.
                    ++skipped;
                    record = {{"input", frame.path}, {"output", job.output}, {"skipped", "the output exists (--skip-existing)"}};
                } else if (frame.path.empty()) {
                    throw InputError("frame " + std::to_string(frame.number) + " is missing (" + input_pattern->path(frame.number) + ")");
                } else {
                    record = run_frame(frame_args, frame.path, job.output, job.raw_output, progress);
                    if (record.contains("failed")) ++failed;
                }
            } catch (const std::exception& e) {
                ++failed;
                progress.message(std::string("error: ") + e.what() + (sequence ? " (skipped; the sequence goes on)" : ""));
                record = {{"input", frame.path}, {"failed", e.what()}};
            }
            if (sequence) record["frame"] = frame.number;
            records[index] = std::move(record);
            progress.update(++done, sequence ? "frame " + std::to_string(frame.number) : path_to_utf8(path_from_utf8(frame.path).filename()));
        }
    };
    const auto start = std::chrono::steady_clock::now();
    if (workers == 1) {
        work();
    } else {
        std::vector<std::thread> pool;
        for (int w = 0; w < workers; ++w) pool.emplace_back(work);
        for (auto& thread : pool) thread.join();
    }
    if (interrupted) progress.message("interrupted: " + std::to_string(done.load()) + " of " + std::to_string(jobs.size()) + " frames done");

    json report;
    report["parameters"] = json::object();
    for (const ParameterSpec& spec : parameter_schema()) {
        if (spec.is_vector()) {
            const auto vector = spec.get_vector(args.parameters);
            report["parameters"][spec.name] = vector ? json(std::vector<double>(vector->begin(), vector->end())) : json(nullptr);
            continue;
        }
        const double value = spec.get(args.parameters);
        if (spec.type == ParameterType::flag)
            report["parameters"][spec.name] = value != 0.0;
        else
            report["parameters"][spec.name] = value;
    }
    report["parameters"]["threads_used"] = threads;
    report["parameters"]["frames_in_parallel"] = workers;
    // How waiting threads behaved (native/core/base/waiting.h): the runtime read these when the process started.
    for (const char* variable : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT", "KMP_BLOCKTIME"}) {
        const char* value = std::getenv(variable);
        report["openmp_wait"][variable] = value ? json(value) : json(nullptr);
    }
    report["frames"] = json::array();
    for (json& record : records)
        if (!record.is_null()) report["frames"].push_back(std::move(record));
    report["total_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report["failed_frames"] = failed.load();
    report["skipped_frames"] = skipped.load();
    report["redone_frames"] = redone.load();
    // Which frames failed, by number in a sequence (by input otherwise), for the farm task's log and for --stats.
    std::string failed_names;
    report["failed"] = json::array();
    for (const json& record : report["frames"])
        if (record.contains("failed")) {
            const json name = record.contains("frame") ? record["frame"] : record["input"];
            report["failed"].push_back(name);
            failed_names += (failed_names.empty() ? "" : ", ") + (name.is_string() ? name.get<std::string>() : name.dump());
        }
    report["peak_memory_bytes"] = peak_rss_bytes();
    if (!args.stats_path.empty()) {
        std::ofstream out(path_from_utf8(args.stats_path), std::ios::binary);  // "\n" line ends on Windows too
        out << report.dump(2) << "\n";
        if (!out) throw FormatError(args.stats_path + ": cannot write the statistics file");
    }
    if (!args.quiet && jobs.size() == 1 && !failed && !report["frames"].empty()) {
        const json& r = report["frames"][0];
        std::fprintf(stderr, "%s: %.0f particles -> %.0f triangles in %.3f s\n", args.input.c_str(), r["counts"]["particles"].get<double>(),
                     r["counts"]["triangles"].get<double>(), r["seconds"]["total"].get<double>());
    }
    if (skipped && !args.quiet)
        std::fprintf(stderr, "%zu of %zu frames skipped: their output exists, made with the same parameters and input\n",
                     skipped.load(), jobs.size());
    if (redone)
        std::fprintf(stderr, "%zu of %zu frames redone: their output was made with other parameters or input\n",
                     redone.load(), jobs.size());
    if (failed) std::fprintf(stderr, "%zu of %zu frames failed: %s\n", failed.load(), jobs.size(), failed_names.c_str());
    if (interrupted) return kExitInterrupted;
    return failed ? 1 : 0;
}

int inspect_command(const std::string& mesh_path, const std::string& raw_path, const std::string& json_path, double particle_radius,
                    int threads) {
    const TriMesh mesh = read_mesh(mesh_path);
    // hfL (analysis/scale_metrics.h) at L = 2 r, its passes set by the raw mesh's mean edge length when there is one.
    const double scale = particle_radius > 0.0 ? 2.0 * particle_radius : 0.0;
    std::optional<MeshQuality> raw;
    if (!raw_path.empty()) raw = assess_quality(read_mesh(raw_path), threads, scale);
    const MeshQuality quality = assess_quality(mesh, threads, scale, raw ? raw->mean_edge_length : 0.0);
    json report;
    report["mesh"] = quality_json(quality);
    report["mesh"]["path"] = mesh_path;
    if (raw) {
        report["raw"] = quality_json(*raw);
        report["raw"]["path"] = raw_path;
        report["volume_ratio"] = raw->volume != 0.0 ? quality.volume / raw->volume : 0.0;
        report["bumpiness_ratio"] = raw->bumpiness > 0.0 ? quality.bumpiness / raw->bumpiness : 0.0;
        if (scale > 0.0) {
            report["hfl_ratio"] = raw->hfl > 0.0 ? quality.hfl / raw->hfl : 0.0;
            report["heat_bumpiness_ratio"] = raw->heat_bumpiness > 0.0 ? quality.heat_bumpiness / raw->heat_bumpiness : 0.0;
        }
    }
    auto print = [](const char* title, const MeshQuality& q) {
        std::printf("%s\n", title);
        std::printf("  topology      %s\n", q.check.summary().c_str());
        std::printf("  size          %zu vertices, %zu triangles\n", q.vertices, q.triangles);
        std::printf("  volume        %.6g (area %.6g)\n", q.volume, q.area);
        std::size_t positive = 0, negative = 0;
        for (const auto& c : q.components) (c.volume >= 0 ? positive : negative)++;
        std::printf("  components    %zu (%zu bodies and droplets, %zu enclosed bubbles)\n", q.components.size(), positive, negative);
        std::printf("  bumpiness     %.6g\n", q.bumpiness);
        if (q.scale_length > 0.0)
            std::printf("  at L = %.6g   hfL %.6g (%d Taubin passes), heat %.6g\n", q.scale_length, q.hfl, q.hfl_passes, q.heat_bumpiness);
        std::printf("  normal angle  %.3f deg (mean between adjacent faces)\n", q.mean_normal_angle_deg);
        std::printf("  barnacles     %zu single-vertex, %zu double-vertex configurations\n", q.single_vertex_configurations,
                    q.double_vertex_configurations);
        std::printf("  valences     ");
        for (std::size_t v = 0; v < q.valence_histogram.size(); ++v)
            if (q.valence_histogram[v]) std::printf(" %zu:%zu", v, q.valence_histogram[v]);
        std::printf("\n");
    };
    print(mesh_path.c_str(), quality);
    if (raw) {
        print(raw_path.c_str(), *raw);
        std::printf("ratios (mesh / raw): volume %.4f, bumpiness %.4f\n", report["volume_ratio"].get<double>(), report["bumpiness_ratio"].get<double>());
        if (scale > 0.0)
            std::printf("ratios at L = 2 r: hfL %.4f, heat %.4f\n", report["hfl_ratio"].get<double>(), report["heat_bumpiness_ratio"].get<double>());
    }
    if (!json_path.empty()) {
        std::ofstream out(path_from_utf8(json_path), std::ios::binary);  // "\n" line ends on Windows too
        out << report.dump(2) << "\n";
        if (!out) throw FormatError(json_path + ": cannot write the report");
    }
    return quality.check.ok() ? 0 : 1;
}

struct ConvertArgs {
    std::string particles, mesh, output;
    bool overwrite = false;
    bool quiet = false;  // accepted for splashsurf's command lines; convert prints one line either way
    std::vector<double> domain_min, domain_max;
};

// splashsurf's convert: particles (any format read_particles reads) to VTK, PLY or XYZ, optionally only those inside
// --domain-min/max; meshes (PLY, OBJ, VTK) to PLY, OBJ or VTK.
int convert_command(const ConvertArgs& args) {
    if (args.particles.empty() == args.mesh.empty()) throw InputError("convert takes one input: --particles FILE or --mesh FILE");
    if (args.domain_min.empty() != args.domain_max.empty())
        throw InputError("--domain-min and --domain-max go together (each three numbers: x y z)");
    if (!args.domain_min.empty() && !args.mesh.empty()) throw InputError("--domain-min/--domain-max apply to --particles only");
    std::error_code error;
    if (fs::exists(path_from_utf8(args.output), error) && !args.overwrite)
        throw InputError(args.output + " exists; pass --overwrite to replace it");
    if (!args.mesh.empty()) {
        const TriMesh mesh = read_mesh(args.mesh);
        write_mesh(mesh, args.output);
        std::printf("%s: %zu vertices, %zu triangles -> %s\n", args.mesh.c_str(), mesh.num_vertices(), mesh.num_triangles(),
                    args.output.c_str());
        return 0;
    }
    ParticleData particles = read_particles(args.particles);
    std::size_t dropped = 0;
    if (!args.domain_min.empty()) {
        const Vector3 lo{args.domain_min[0], args.domain_min[1], args.domain_min[2]};
        const Vector3 hi{args.domain_max[0], args.domain_max[1], args.domain_max[2]};
        for (int k = 0; k < 3; ++k)
            if (!(lo[k] < hi[k]))
                throw InputError("--domain-min must be below --domain-max in every coordinate, got " + format_number(lo[k]) +
                                 " and " + format_number(hi[k]) + " in " + "xyz"[k]);
        dropped = keep_particles_in_box(particles, lo, hi);
    }
    write_particles(particles, args.output);
    std::printf("%s: %zu particles (%zu outside the domain dropped) -> %s\n", args.particles.c_str(), particles.size(), dropped,
                args.output.c_str());
    return 0;
}

}  // namespace

namespace meniscus {

int run_cli(const std::vector<std::string>& arguments, const CliHooks& hooks) {
    CLI::App app{"meniscus " MENISCUS_VERSION ": smooth fluid surfaces from particle data"};
    app.require_subcommand(1);
    app.allow_windows_style_options(false);  // CLI11's Windows default reads a path like /data/x.vtk as an option

    ReconstructArgs args;
    CLI::App* reconstruct = app.add_subcommand("reconstruct", "Reconstruct the surface of a particle file or sequence");
    reconstruct->add_option("input", args.input,
                            "Particle file (VTK, VTU, BGEO, Houdini JSON, PLY, XYZ, NPY/NPZ, CSV); {} or #### in the name "
                            "stands for the frame number (required unless --parameters gives it)");
    reconstruct->add_option("-o,--output-file", args.output,
                            "Output mesh (.ply, .obj, .vtk); {} or #### for the frame number (default: {input name}_surface.vtk)");
    reconstruct->add_option("--output-dir", args.output_dir, "Folder for the output files (created if missing; default: the current folder)");
    // Checked as typed, before conversion: a number beyond 64 bits would reach the range check clamped.
    const CLI::Validator frame_number(
        [](std::string& text) -> std::string {
            const bool digits = text.size() <= 11 && std::regex_match(text, std::regex(R"(-?\d+)"));
            if (digits && !frame_number_problem(std::stoll(text))) return "";
            return "must be " + allowed_frame_numbers() + ", got " + text;
        },
        "FRAME");
    reconstruct->add_option("-s,--start-index", args.start, "First frame of a sequence")->check(frame_number);
    reconstruct->add_option("-e,--end-index", args.end, "Last frame of a sequence")->check(frame_number);
    reconstruct->add_option("--frames", args.frames, "Frames FIRST-LAST of a sequence (a farm task's chunk), instead of -s/-e")
        ->excludes("-s")->excludes("-e");
    reconstruct->add_option("--parameters", args.parameters_path,
                            "Read the input, output, frames and pipeline parameters from this JSON file (flags given beside it "
                            "win); written by --save-parameters, the Python API and the Blender add-on");
    reconstruct->add_option("--save-parameters", args.save_parameters_path,
                            "Write every pipeline parameter with the input, output and frames to this JSON file and stop "
                            "(nothing is reconstructed)");
    reconstruct->add_flag("--skip-existing", args.skip_existing,
                          "Skip frames whose output exists and was made with the same parameters and particle file (its record "
                          "OUTPUT.meniscus says; others are redone). Outputs are written under a temporary name and renamed when "
                          "complete, so an existing one is complete: a re-queued farm task redoes only what is missing or stale");
    reconstruct->add_option("--stats", args.stats_path, "Write per-stage seconds, counts and peak memory as JSON");
    reconstruct->add_option("-a,--interpolate-attribute,--interpolate_attribute", args.attributes,
                            "Particle attribute to carry onto the mesh (repeatable); whole-number fields (ids) come from the "
                            "nearest particle");
    reconstruct->add_option("--output-raw-mesh", args.raw_output,
                            "Also write the mesh before post-processing: a path ({} for the frame number), or on for "
                            "<output>_raw beside the output");
    add_switch(*reconstruct, "--check-mesh", args.check, "Check closed, manifold, oriented; a failing frame is reported");
    for (const char* check : {"--check-mesh-closed", "--check-mesh-manifold", "--check-mesh-orientation"})
        add_switch(*reconstruct, check, args.check, "Same as --check-mesh (which checks all three)")->group("splashsurf compatibility");
    add_switch(*reconstruct, "--mt-files", args.frames_in_parallel,
               "Reconstruct several frames of a sequence at once, sharing the threads (faster for many small frames)");
    add_switch(*reconstruct, "--mt-particles", args.threads_per_frame,
               "Use several threads within each frame (off with --mt-files: one thread per frame)");
    add_compatibility_flags(*reconstruct, args);
    add_parameter_flags(*reconstruct, args.parameters);
    reconstruct->add_flag("-q,--quiet", args.quiet, "No progress bar or summary");

    std::string mesh_path, raw_path, json_path;
    int inspect_threads = 0;
    CLI::App* inspect = app.add_subcommand("inspect", "Quality report of a mesh (topology, volume, components, bumpiness)");
    inspect->add_option("mesh", mesh_path, "Mesh file (.ply, .obj)")->required();
    inspect->add_option("--raw", raw_path, "The raw mesh, for volume and bumpiness ratios");
    inspect->add_option("--json", json_path, "Write the report as JSON");
    inspect->add_option("-n,--threads", inspect_threads, "Threads (0: all cores)");
    double inspect_radius = 0.0;
    inspect->add_option("-r,--particle-radius", inspect_radius,
                        "Particle radius: adds the bumpiness at L = 2 r (hfL, with --raw its ratio; Taubin passes from the raw "
                        "mesh's mean edge length) and its heat-kernel variant");

    ConvertArgs convert_args;
    CLI::App* convert = app.add_subcommand("convert", "Convert particle or mesh files between formats (as splashsurf convert)");
    convert->add_option("--particles", convert_args.particles, "Particle file to read (every format reconstruct reads)");
    convert->add_option("--mesh", convert_args.mesh, "Mesh file to read (.ply, .obj, .vtk)");
    convert->add_option("-o", convert_args.output, "Output file: particles to .vtk, .ply, .xyz; meshes to .ply, .obj, .vtk")->required();
    convert->add_flag("--overwrite", convert_args.overwrite, "Replace an existing output file");
    convert->add_option("--domain-min", convert_args.domain_min, "Lower corner of the box of particles to keep")->expected(3)->type_name("X Y Z");
    convert->add_option("--domain-max", convert_args.domain_max, "Upper corner of the box of particles to keep")->expected(3)->type_name("X Y Z");
    convert->add_flag("-q,--quiet", convert_args.quiet, "Accepted for splashsurf's command lines");

    // Farm jobs are made by the Python console script, which has the bundle writer and Dask; this executable runs
    // their tasks. Named here so that `meniscus farm` says where to go rather than "unknown command".
    CLI::App* farm = app.add_subcommand("farm", "Farm jobs (OpenJD / Deadline Cloud bundles, Dask): in the Python console script");
    farm->allow_extras()->prefix_command();

    // splashsurf's command lines write short options as -r=0.025; CLI11 reads that as the value "=0.025".
    std::vector<std::string> split;
    for (const auto& argument : arguments) {
        if (argument.size() > 3 && argument[0] == '-' && argument[1] != '-' && argument[2] == '=') {
            split.push_back(argument.substr(0, 2));
            split.push_back(argument.substr(3));
        } else {
            split.push_back(argument);
        }
    }
    // --parameters FILE fills the arguments before the flags are parsed, so that flags given beside it win.
    if (split.size() > 1 && split[1] == "reconstruct") {
        for (std::size_t i = 2; i < split.size(); ++i) {
            std::string path;
            if (split[i] == "--parameters" && i + 1 < split.size()) path = split[i + 1];
            if (split[i].rfind("--parameters=", 0) == 0) path = split[i].substr(13);
            if (path.empty()) continue;
            try {
                ParametersFile file = read_parameters_file(path);
                args.parameters = file.parameters;
                if (file.input) args.input = *file.input;
                if (file.output) args.output = *file.output;
                args.start = file.start;
                args.end = file.end;
                if (file.attributes) args.attributes = *file.attributes;
            } catch (const std::exception& e) {
                std::fprintf(stderr, "error: --parameters %s\n", e.what());
                return 2;
            }
        }
    }
    std::vector<const char*> argv;
    for (const auto& argument : split) argv.push_back(argument.c_str());
    try {
        app.parse(static_cast<int>(argv.size()), argv.data());
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;  // --help is not an error; every usage error is status 2
    }
    try {
        if (*reconstruct) return reconstruct_command(args, hooks);
        if (*inspect) return inspect_command(mesh_path, raw_path, json_path, inspect_radius, inspect_threads);
        if (*convert) return convert_command(convert_args);
        if (*farm) {
            std::fprintf(stderr, "meniscus farm is part of the Python console script: pip install meniscus (plus \"meniscus[dask]\" "
                                 "for Dask), then `meniscus farm openjd ...` or `python -m meniscus farm ...`; see docs/farm.md. "
                                 "This executable runs the farm's tasks (reconstruct --parameters FILE --frames A-B).\n");
            return 2;
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}

}  // namespace meniscus
