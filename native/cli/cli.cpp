// The meniscus command line, for batch and render-farm use; flags follow splashsurf where it has them. It runs
// as the `meniscus` executable (main.cpp) and inside the Python module (`meniscus` console script of the wheel).
//   meniscus reconstruct INPUT -o OUTPUT -r R [-l L] [-c C] [-t T] [-s S -e E] [--threads N] [--stats FILE] ...
//   meniscus inspect MESH [--raw RAW] [--json FILE]
#include "cli.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <vector>

#include "base/errors.h"
#include "io/io.h"
#include "io/io_util.h"
#include "base/memory.h"
#include "base/parallel.h"
#include "parameters.h"
#include "pipeline.h"
#include "base/platform.h"
#include "analysis/quality.h"
#include "surface/reconstruction.h"

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace meniscus;

namespace {

// ---- sequences ------------------------------------------------------------------------------------------------
// "{}" in a file name stands for the frame number, with or without zero padding: frames are found by listing the
// folder, so fluid_{}.vtk matches fluid_7.vtk and fluid_0007.vtk alike.
struct Frame {
    long number;
    std::string digits;  // as written in the input name, reused for the output name
    std::string path;
};

bool is_sequence(const std::string& pattern) { return pattern.find("{}") != std::string::npos; }

std::string substitute(const std::string& pattern, const std::string& digits) {
    std::string out = pattern;
    const auto at = out.find("{}");
    if (at != std::string::npos) out.replace(at, 2, digits);
    return out;
}

std::vector<Frame> find_frames(const std::string& pattern) {
    const fs::path path = path_from_utf8(pattern);
    const std::string name = path_to_utf8(path.filename());
    const auto at = name.find("{}");
    if (at == std::string::npos) throw InputError("input pattern '" + pattern + "': '{}' must be in the file name, not the folder");
    const std::string prefix = name.substr(0, at), suffix = name.substr(at + 2);
    const fs::path folder = path.has_parent_path() ? path.parent_path() : fs::path(".");
    std::error_code error;
    if (!fs::is_directory(folder, error)) throw InputError("input pattern '" + pattern + "': folder '" + path_to_utf8(folder) + "' does not exist");
    std::map<long, Frame> frames;
    for (const auto& entry : fs::directory_iterator(folder, error)) {
        const std::string file = path_to_utf8(entry.path().filename());
        if (file.size() <= prefix.size() + suffix.size() || file.compare(0, prefix.size(), prefix) != 0 ||
            file.compare(file.size() - suffix.size(), suffix.size(), suffix) != 0)
            continue;
        const std::string digits = file.substr(prefix.size(), file.size() - prefix.size() - suffix.size());
        if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
        const long number = std::stol(digits);
        // Duplicate frame numbers (fluid_7 and fluid_007): keep the first name in sorted order, deterministically,
        // and say so.
        auto it = frames.find(number);
        const std::string full = path_to_utf8(folder / entry.path().filename());
        if (it != frames.end())
            std::fprintf(stderr, "warning: frame %ld matches both %s and %s; using %s\n", number, it->second.path.c_str(), full.c_str(),
                         std::min(full, it->second.path).c_str());
        if (it == frames.end() || full < it->second.path) frames[number] = {number, digits, full};
    }
    std::vector<Frame> result;
    for (auto& kv : frames) result.push_back(kv.second);
    return result;
}

// ---- progress -------------------------------------------------------------------------------------------------
class Progress {
public:
    Progress(std::size_t total, bool enabled) : total_(total), enabled_(enabled && total > 1), start_(std::chrono::steady_clock::now()) {}
    void update(std::size_t done, const std::string& label) {
        if (!enabled_) return;
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
        std::fprintf(stderr, "%s%s\n", enabled_ ? "\n" : "", text.c_str());
        std::fflush(stderr);
    }

private:
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
            {"double_vertex_configurations", q.double_vertex_configurations}};
}

struct ReconstructArgs {
    std::string input, output, raw_output, stats_path;
    Parameters parameters;  // the pipeline's, filled from the schema's flags
    std::optional<long> start, end;
    std::vector<std::string> attributes;
    bool check = false;
    bool quiet = false;
};

// The text of a schema parameter's command-line value as a number: on|off for switches, the automatic word
// (auto, all) where there is one, a number otherwise. Errors name the flag in the user's spelling.
double parse_parameter(const ParameterSpec& spec, const std::string& flag, const std::string& text) {
    double value = 0.0;
    if (spec.cli_style == CliStyle::on_off) {
        if (text == "on" || text == "true" || text == "1" || text == "yes") return 1.0;
        if (text == "off" || text == "false" || text == "0" || text == "no") return 0.0;
        throw CLI::ValidationError(flag, "takes on or off, got '" + text + "'");
    }
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

// One flag per schema parameter, with its help text, unit, allowed values and default.
void add_parameter_flags(CLI::App& command, Parameters& parameters) {
    for (const ParameterSpec& spec : parameter_schema()) {
        // The name messages use: the first long name (-r,--particle-radius -> --particle-radius).
        const std::size_t long_start = spec.cli.find("--");
        const std::string flag = spec.cli.substr(long_start, spec.cli.find(',', long_start) - long_start);
        std::string help = spec.help;
        if (!spec.unit.empty()) help += " [" + spec.unit + "]";
        if (spec.cli_style == CliStyle::flag) {
            command.add_flag_callback(spec.cli, [&parameters, &spec] { spec.set(parameters, 1.0); }, help);
            continue;
        }
        if (spec.cli_style == CliStyle::value) help += "; " + spec.allowed();
        CLI::Option* option = command.add_option_function<std::string>(
            spec.cli, [&parameters, &spec, flag](const std::string& text) { spec.set(parameters, parse_parameter(spec, flag, text)); },
            help);
        option->type_name(spec.cli_style == CliStyle::on_off ? "on|off" : spec.automatic ? "NUMBER|" + spec.automatic_word : "NUMBER");
        if (spec.required)
            option->required();
        else
            option->default_str(cli_value_text(spec, spec.default_value()));
    }
}

// Runs one frame; returns the frame's JSON record. Throws on failure (the caller reports and goes on).
json run_frame(const ReconstructArgs& args, const std::string& input, const std::string& output, const std::string& raw_output,
               Progress& progress) {
    const auto start = std::chrono::steady_clock::now();
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
    if (!output.empty()) write_mesh(result.mesh, output);
    if (!raw_output.empty()) write_mesh(result.raw_mesh, raw_output);
    result.stats.add_seconds("write", std::chrono::duration<double>(std::chrono::steady_clock::now() - write_start).count());
    json stats = stats_json(result.stats);
    for (auto& item : stats.items()) record[item.key()] = item.value();
    record["peak_memory_bytes"] = peak_rss_bytes();
    if (args.check && !record["check"]["ok"].get<bool>()) record["failed"] = "mesh check";
    return record;
}

int reconstruct_command(ReconstructArgs& args, const CliHooks& hooks) {
    validate(args.parameters);

    std::vector<Frame> frames;
    const bool sequence = is_sequence(args.input);
    if (sequence) {
        if (!args.output.empty() && !is_sequence(args.output)) throw InputError("output '" + args.output + "' needs '{}' for a sequence input");
        if (!args.raw_output.empty() && !is_sequence(args.raw_output))
            throw InputError("--output-raw-mesh '" + args.raw_output + "' needs '{}' for a sequence input");
        std::vector<Frame> found = find_frames(args.input);
        const long first = args.start ? *args.start : (found.empty() ? 0 : found.front().number);
        const long last = args.end ? *args.end : (found.empty() ? -1 : found.back().number);
        std::map<long, Frame> by_number;
        for (auto& f : found) by_number[f.number] = f;
        // Every frame of the range is attempted; one that is missing is reported like a broken one.
        for (long n = first; n <= last; ++n) {
            auto it = by_number.find(n);
            frames.push_back(it != by_number.end() ? it->second : Frame{n, std::to_string(n), ""});
        }
        if (frames.empty()) throw InputError("no frames match '" + args.input + "'");
    } else {
        frames.push_back({0, "", args.input});
    }

    Progress progress(frames.size(), !args.quiet && is_terminal(stderr));
    json report;
    report["parameters"] = json::object();
    for (const ParameterSpec& spec : parameter_schema()) {
        const double value = spec.get(args.parameters);
        if (spec.type == ParameterType::flag)
            report["parameters"][spec.name] = value != 0.0;
        else
            report["parameters"][spec.name] = value;
    }
    report["parameters"]["threads_used"] = resolve_threads(args.parameters.execution.threads);
    report["frames"] = json::array();
    std::size_t failed = 0, done = 0;
    const auto start = std::chrono::steady_clock::now();
    bool interrupted = false;
    for (const Frame& frame : frames) {
        if (hooks.interrupted && hooks.interrupted()) {  // between frames: a frame once started runs to its end
            progress.message("interrupted: " + std::to_string(done) + " of " + std::to_string(frames.size()) + " frames done");
            interrupted = true;
            break;
        }
        const std::string label = sequence ? "frame " + std::to_string(frame.number) : path_to_utf8(path_from_utf8(frame.path).filename());
        json record;
        try {
            if (frame.path.empty()) throw InputError("frame " + std::to_string(frame.number) + " is missing (" + substitute(args.input, "<" + std::to_string(frame.number) + ">") + ")");
            record = run_frame(args, frame.path, sequence ? substitute(args.output, frame.digits) : args.output,
                               sequence ? substitute(args.raw_output, frame.digits) : args.raw_output, progress);
            if (record.contains("failed")) ++failed;
        } catch (const std::exception& e) {
            ++failed;
            progress.message(std::string("error: ") + e.what() + (sequence ? " (skipped; the sequence goes on)" : ""));
            record = {{"input", frame.path}, {"failed", e.what()}};
        }
        if (sequence) record["frame"] = frame.number;
        report["frames"].push_back(record);
        progress.update(++done, label);
    }
    report["total_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report["failed_frames"] = failed;
    report["peak_memory_bytes"] = peak_rss_bytes();
    if (!args.stats_path.empty()) {
        std::ofstream out(path_from_utf8(args.stats_path));
        out << report.dump(2) << "\n";
        if (!out) throw FormatError(args.stats_path + ": cannot write the statistics file");
    }
    if (!args.quiet && frames.size() == 1 && !failed) {
        const json& r = report["frames"][0];
        std::fprintf(stderr, "%s: %.0f particles -> %.0f triangles in %.3f s\n", args.input.c_str(), r["counts"]["particles"].get<double>(),
                     r["counts"]["triangles"].get<double>(), r["seconds"]["total"].get<double>());
    }
    if (failed) std::fprintf(stderr, "%zu of %zu frames failed\n", failed, frames.size());
    if (interrupted) return kExitInterrupted;
    return failed ? 1 : 0;
}

int inspect_command(const std::string& mesh_path, const std::string& raw_path, const std::string& json_path, int threads) {
    const TriMesh mesh = read_mesh(mesh_path);
    const MeshQuality quality = assess_quality(mesh, threads);
    json report;
    report["mesh"] = quality_json(quality);
    report["mesh"]["path"] = mesh_path;
    std::optional<MeshQuality> raw;
    if (!raw_path.empty()) {
        raw = assess_quality(read_mesh(raw_path), threads);
        report["raw"] = quality_json(*raw);
        report["raw"]["path"] = raw_path;
        report["volume_ratio"] = raw->volume != 0.0 ? quality.volume / raw->volume : 0.0;
        report["bumpiness_ratio"] = raw->bumpiness > 0.0 ? quality.bumpiness / raw->bumpiness : 0.0;
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
    }
    if (!json_path.empty()) {
        std::ofstream out(path_from_utf8(json_path));
        out << report.dump(2) << "\n";
        if (!out) throw FormatError(json_path + ": cannot write the report");
    }
    return quality.check.ok() ? 0 : 1;
}

}  // namespace

namespace meniscus {

int run_cli(const std::vector<std::string>& arguments, const CliHooks& hooks) {
    CLI::App app{"meniscus " MENISCUS_VERSION ": smooth fluid surfaces from particle data"};
    app.require_subcommand(1);
    app.allow_windows_style_options(false);  // CLI11's Windows default reads a path like /data/x.vtk as an option

    ReconstructArgs args;
    CLI::App* reconstruct = app.add_subcommand("reconstruct", "Reconstruct the surface of a particle file or sequence");
    reconstruct->add_option("input", args.input, "Particle file (VTK, VTU, BGEO, PLY, XYZ, NPY/NPZ, CSV); '{}' in the name stands for the frame number")->required();
    reconstruct->add_option("-o,--output-file", args.output, "Output mesh (.ply, .obj, .vtk); '{}' for the frame number")->required();
    reconstruct->add_option("-s,--start-index", args.start, "First frame of a sequence");
    reconstruct->add_option("-e,--end-index", args.end, "Last frame of a sequence");
    reconstruct->add_option("--stats", args.stats_path, "Write per-stage seconds, counts and peak memory as JSON");
    reconstruct->add_option("-a,--interpolate-attribute", args.attributes,
                            "Particle attribute to carry onto the mesh (repeatable); whole-number fields (ids) come from the "
                            "nearest particle");
    reconstruct->add_option("--output-raw-mesh", args.raw_output, "Also write the mesh before post-processing");
    reconstruct->add_flag("--check-mesh", args.check, "Check closed, manifold, oriented; a failing frame is reported");
    add_parameter_flags(*reconstruct, args.parameters);
    reconstruct->add_flag("-q,--quiet", args.quiet, "No progress bar or summary");

    std::string mesh_path, raw_path, json_path;
    int inspect_threads = 0;
    CLI::App* inspect = app.add_subcommand("inspect", "Quality report of a mesh (topology, volume, components, bumpiness)");
    inspect->add_option("mesh", mesh_path, "Mesh file (.ply, .obj)")->required();
    inspect->add_option("--raw", raw_path, "The raw mesh, for volume and bumpiness ratios");
    inspect->add_option("--json", json_path, "Write the report as JSON");
    inspect->add_option("-n,--threads", inspect_threads, "Threads (0: all cores)");

    std::vector<const char*> argv;
    for (const auto& argument : arguments) argv.push_back(argument.c_str());
    try {
        app.parse(static_cast<int>(argv.size()), argv.data());
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;  // --help is not an error; every usage error is status 2
    }
    try {
        if (*reconstruct) return reconstruct_command(args, hooks);
        if (*inspect) return inspect_command(mesh_path, raw_path, json_path, inspect_threads);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 2;
    }
    return 0;
}

}  // namespace meniscus
