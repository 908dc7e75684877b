#include "io/provenance.h"

#include <chrono>
#include <cinttypes>
#include <initializer_list>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "base/errors.h"
#include "base/platform.h"
#include "io/partial_files.h"

namespace fs = std::filesystem;

namespace meniscus {

namespace {

constexpr const char* kHeader = "meniscus-provenance 1";

// Values at single precision, written exactly (9 significant digits): Blender stores its settings as floats, so the
// add-on's 0.02500000037252903 and a parameters file's 0.025 are the same radius (no mesh changes below that).
std::string exact(double value) {
    char text[40];
    std::snprintf(text, sizeof text, "%.9g", static_cast<double>(static_cast<float>(value)));
    return text;
}

bool shapes_the_mesh(const ParameterSpec& spec) { return spec.name != "threads" && spec.name != "memory_budget"; }

// Whether a parameter takes part, by the schema's depends_on ("smoothing_iterations,!smoothing_reach"): one that
// does not (the quad limits without quads) is recorded as unused, so changing it leaves the meshes current.
bool takes_part(const ParameterSpec& spec, const Parameters& parameters) {
    std::istringstream conditions(spec.depends_on);
    std::string condition;
    while (std::getline(conditions, condition, ',')) {
        const bool negated = !condition.empty() && condition[0] == '!';
        const ParameterSpec& other = find_parameter(condition.substr(negated ? 1 : 0));
        if ((other.get(parameters) != 0.0) == negated || !takes_part(other, parameters)) return false;
    }
    return true;
}

// FNV-1a, 64 bits: a short, stable name for the parameter lines (a check of equality, not a security measure).
constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;

std::uint64_t fnv1a(std::uint64_t hash, const void* data, std::size_t size) {
    const unsigned char* bytes = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
    return hash;
}

std::string hex_of(std::uint64_t hash) {
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016" PRIx64, hash);
    return hex;
}

std::string digest_of(const std::string& text) { return hex_of(fnv1a(kFnvOffset, text.data(), text.size())); }

// Every value of a fluid domain, bit for bit (obstacles run to millions of floats: hashed, not written out).
std::string digest_of(const FluidDomain& d) {
    std::uint64_t hash = kFnvOffset;
    auto number = [&](double value) { hash = fnv1a(hash, &value, sizeof value); };
    for (double v : d.origin) number(v);
    for (const auto& axis : d.axes)
        for (double v : axis) number(v);
    for (int v : d.resolution) number(v);
    for (bool v : d.closed_borders) number(v ? 1.0 : 0.0);
    for (double v : d.gravity) number(v);
    number(d.band_width_cells);
    for (double v : d.object_to_world) number(v);
    for (double v : {double(d.mesh_upres), d.mesh_particle_radius, double(d.mesh_smoothen_pos), double(d.mesh_smoothen_neg), d.mesh_concave_lower,
                     d.mesh_concave_upper})
        number(v);
    for (const std::vector<float>& soup : d.obstacles) {
        number(static_cast<double>(soup.size()));  // where one obstacle ends and the next begins
        hash = fnv1a(hash, soup.data(), soup.size() * sizeof(float));
    }
    return hex_of(hash);
}

// A value as people write it (0.025, not 0.025000000000000001); vectors and words as they are.
std::string readable(const std::string& value) {
    if (value.empty()) return "none";
    char* end = nullptr;
    const float number = std::strtof(value.c_str(), &end);
    if (!end || *end != '\0') return value;
    char text[40];
    for (int digits = 1; digits <= 9; ++digits) {  // the shortest spelling of the same float
        std::snprintf(text, sizeof text, "%.*g", digits, static_cast<double>(number));
        if (std::strtof(text, nullptr) == number) break;
    }
    return text;
}

using Lines = std::vector<std::pair<std::string, std::string>>;  // key, value, in the record's order

Lines parse(const std::string& record) {
    Lines lines;
    std::istringstream in(record);
    std::string line;
    while (std::getline(in, line)) {
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const std::size_t space = line.find(' ');
        lines.emplace_back(line.substr(0, space), space == std::string::npos ? std::string() : line.substr(space + 1));
    }
    return lines;
}

const std::string* find(const Lines& lines, const std::string& key) {
    for (const auto& [k, v] : lines)
        if (k == key) return &v;
    return nullptr;
}

}  // namespace

std::string provenance_record(const Parameters& parameters, const std::vector<std::string>& attributes,
                              const std::string& source_path, const FluidDomain* fluid_domain) {
    std::string shaping;
    for (const ParameterSpec& spec : parameter_schema()) {
        if (!shapes_the_mesh(spec)) continue;
        std::string value;
        if (!takes_part(spec, parameters)) {
            value = "unused";
        } else if (spec.is_vector()) {
            const auto vector = spec.get_vector(parameters);
            value = vector ? exact((*vector)[0]) + "," + exact((*vector)[1]) + "," + exact((*vector)[2]) : "none";
        } else {
            value = exact(spec.get(parameters));
        }
        shaping += "parameter:" + spec.name + " " + value + "\n";
    }
    std::string names;
    for (const std::string& name : attributes) names += (names.empty() ? "" : ",") + name;
    shaping += "attributes " + names + "\n";
    if (fluid_domain) shaping += "fluid_domain " + digest_of(*fluid_domain) + "\n";

    const std::string head = std::string(kHeader) + "\ndigest " + digest_of(shaping) + "\n";
    if (source_path.empty()) return head + shaping;  // a check of the parameters alone (the particle file is gone)
    const fs::path source = path_from_utf8(source_path);
    std::error_code error;
    const std::uintmax_t size = fs::file_size(source, error);
    if (error) throw FormatError(source_path + ": cannot read the particle file's size (" + error.message() + ")");
    const auto modified = fs::last_write_time(source, error);
    if (error) throw FormatError(source_path + ": cannot read the particle file's time (" + error.message() + ")");
    const long long ticks =
        static_cast<long long>(std::chrono::duration_cast<std::chrono::nanoseconds>(modified.time_since_epoch()).count());
    // The name, not the folder: a project moved with its files keeps its meshes current.
    return head + "source " + path_to_utf8(source.filename()) +
           "\nsource_size " + std::to_string(size) + "\nsource_modified " + std::to_string(ticks) + "\n" + shaping;
}

std::string provenance_path(const std::string& mesh_path) { return mesh_path + ".meniscus"; }

void forget_provenance(const std::string& mesh_path) {
    std::error_code ignored;
    fs::remove(path_from_utf8(provenance_path(mesh_path)), ignored);
}

void write_provenance(const std::string& mesh_path, const std::string& record) {
    const std::string target = provenance_path(mesh_path);
    // Named after this process: a writer killed before the rename leaves a file the next writer can tell abandoned.
    const std::string temporary = partial_path(target, current_process_id());
    {
        std::ofstream out(path_from_utf8(temporary), std::ios::binary);
        out << record;
        out.close();
        if (!out) {
            remove_file(temporary);
            throw FormatError(target + ": cannot write the mesh's provenance record");
        }
    }
    std::error_code error;
    fs::rename(path_from_utf8(temporary), path_from_utf8(target), error);
    if (error) {
        remove_file(temporary);
        throw FormatError(target + ": cannot move the provenance record into place (" + error.message() + ")");
    }
}

std::string provenance_mismatch(const std::string& mesh_path, const std::string& expected) {
    std::ifstream in(path_from_utf8(provenance_path(mesh_path)), std::ios::binary);
    if (!in) return "no record of what it was made from";
    std::ostringstream text;
    text << in.rdbuf();
    const Lines found = parse(text.str()), wanted = parse(expected);
    if (found.empty() || found.front().first + " " + found.front().second != kHeader)
        return "its record of what it was made from is unreadable";
    const std::string* digest = find(found, "digest");
    const std::string* wanted_digest = find(wanted, "digest");
    if (!digest || !wanted_digest || *digest != *wanted_digest) {
        for (const auto& [key, value] : wanted) {
            const bool parameter = key.rfind("parameter:", 0) == 0;
            if (!parameter && key != "attributes" && key != "fluid_domain") continue;
            const std::string* had = find(found, key);
            if (had && *had == value) continue;
            if (key == "fluid_domain")  // a digest says nothing to a person: what it covers does
                return "made with another fluid domain (its borders, narrow band, gravity, grid, obstacles, place or mesh settings)";
            const std::string name = parameter ? key.substr(10) : "interpolated attributes";
            return "made with " + name + " " + (had ? readable(*had) : "unknown") + ", now " + readable(value);
        }
        if (find(found, "fluid_domain") && !find(wanted, "fluid_domain"))  // a fluid domain then, none now
            return "made with a fluid domain, now without";
        return "made with other parameters";
    }
    const std::string* source = find(found, "source");
    const std::string* wanted_source = find(wanted, "source");
    if (!wanted_source) return "";  // the parameters alone were asked about
    if (!source || !wanted_source || *source != *wanted_source)
        return "made from " + (source ? *source : std::string("another file")) + ", now " +
               (wanted_source ? *wanted_source : std::string("another file"));
    for (const char* key : {"source_size", "source_modified"}) {
        const std::string* had = find(found, key);
        const std::string* now = find(wanted, key);
        if (!had || !now || *had != *now)
            return "its particle file " + *source + " changed since (size or modification time)";
    }
    return "";
}

}  // namespace meniscus
