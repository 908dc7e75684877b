#include "parameters_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "base/errors.h"
#include "base/platform.h"

namespace meniscus {

namespace {

// ordered: the file lists the keys in the order written (the version first, the parameters in schema order).
using json = nlohmann::ordered_json;

const char* const kVersionKey = "meniscus_parameters";
const std::vector<std::string> kTopKeys = {kVersionKey, "input", "output", "start", "end", "interpolate_attributes", "parameters"};

std::string joined(const std::vector<std::string>& names) {
    std::string text;
    for (const auto& name : names) text += (text.empty() ? "" : ", ") + name;
    return text;
}

// The value as JSON writes it back, for messages: "big", [1,2], true.
std::string shown(const json& value) {
    std::string text = value.dump();
    return text.size() > 60 ? text.substr(0, 57) + "..." : text;
}

[[noreturn]] void refuse(const std::string& source, const std::string& key, const std::string& what) {
    throw InputError(source + ": " + key + ": " + what);
}

double schema_number(const ParameterSpec& spec, const json& value, const std::string& source, const std::string& key) {
    if (spec.type == ParameterType::flag) {
        if (!value.is_boolean()) refuse(source, key, "must be true or false, got " + shown(value));
        return value.get<bool>() ? 1.0 : 0.0;
    }
    if (!value.is_number()) refuse(source, key, "must be " + spec.allowed() + ", got " + shown(value));
    const double number = value.get<double>();
    if (auto problem = spec.problem(number)) refuse(source, key, *problem);
    return number;
}

std::optional<Vector3> schema_vector(const ParameterSpec& spec, const json& value, const std::string& source, const std::string& key) {
    if (value.is_null()) return std::nullopt;
    if (!value.is_array() || value.size() != 3 || !std::all_of(value.begin(), value.end(), [](const json& x) { return x.is_number(); }))
        refuse(source, key, "must be three numbers [x, y, z] or null (unset), got " + shown(value));
    const Vector3 vector{value[0].get<double>(), value[1].get<double>(), value[2].get<double>()};
    if (auto problem = spec.problem(std::optional<Vector3>(vector))) refuse(source, key, *problem);
    return vector;
}

std::string text_of(const json& value, const std::string& source, const std::string& key) {
    if (!value.is_string()) refuse(source, key, "must be a text (a path), got " + shown(value));
    return value.get<std::string>();
}

long frame_of(const json& value, const std::string& source, const std::string& key) {
    if (!value.is_number_integer()) refuse(source, key, "must be a whole frame number, got " + shown(value));
    // Read wide: 18446744073709551615 (unsigned in JSON) must not wrap round to -1.
    if (value.is_number_unsigned() && value.get<unsigned long long>() > static_cast<unsigned long long>(kMaxFrameNumber))
        refuse(source, key, "must be " + allowed_frame_numbers() + ", got " + shown(value));
    if (auto problem = frame_number_problem(value.get<long long>())) refuse(source, key, *problem);
    return static_cast<long>(value.get<long long>());
}

}  // namespace

std::string allowed_frame_numbers() {
    return "a frame number from " + std::to_string(-kMaxFrameNumber) + " to " + std::to_string(kMaxFrameNumber);
}

std::optional<std::string> frame_number_problem(long long frame) {
    if (frame >= -kMaxFrameNumber && frame <= kMaxFrameNumber) return std::nullopt;
    return "must be " + allowed_frame_numbers() + ", got " + std::to_string(frame);
}

std::optional<std::string> frame_range_problem(long long first, long long last) {
    if (auto problem = frame_number_problem(first)) return "the first frame " + *problem;
    if (auto problem = frame_number_problem(last)) return "the last frame " + *problem;
    if (last - first + 1 > kMaxFrameCount)
        return "frames " + std::to_string(first) + "-" + std::to_string(last) + " are " + std::to_string(last - first + 1) +
               " frames, more than the " + std::to_string(kMaxFrameCount) + " one run takes (split the range)";
    return std::nullopt;
}

std::string parameters_file_text(const ParametersFile& file) {
    json out = json::object();
    out[kVersionKey] = kParametersFileVersion;
    if (file.input) out["input"] = *file.input;
    if (file.output) out["output"] = *file.output;
    if (file.start) out["start"] = *file.start;
    if (file.end) out["end"] = *file.end;
    if (file.attributes) out["interpolate_attributes"] = *file.attributes;
    json parameters = json::object();
    for (const ParameterSpec& spec : parameter_schema()) {
        if (spec.is_vector()) {
            const auto vector = spec.get_vector(file.parameters);
            parameters[spec.name] = vector ? json(std::vector<double>(vector->begin(), vector->end())) : json(nullptr);
        } else if (spec.type == ParameterType::flag) {
            parameters[spec.name] = spec.get(file.parameters) != 0.0;
        } else if (spec.type == ParameterType::count) {
            parameters[spec.name] = static_cast<long long>(spec.get(file.parameters));
        } else {
            parameters[spec.name] = spec.get(file.parameters);
        }
    }
    out["parameters"] = std::move(parameters);
    return out.dump(2) + "\n";
}

ParametersFile parse_parameters_file(const std::string& text, const std::string& source) {
    json root;
    try {
        root = json::parse(text);
    } catch (const json::parse_error& e) {
        throw InputError(source + ": not a JSON parameters file (" + e.what() + ")");
    }
    if (!root.is_object()) throw InputError(source + ": a parameters file is a JSON object {\"meniscus_parameters\": 1, ...}");
    for (const auto& item : root.items())
        if (std::find(kTopKeys.begin(), kTopKeys.end(), item.key()) == kTopKeys.end())
            refuse(source, item.key(), "unknown key (a parameters file has: " + joined(kTopKeys) + ")");
    if (!root.contains(kVersionKey)) refuse(source, kVersionKey, "missing: this is not a Meniscus parameters file");
    if (!root[kVersionKey].is_number_integer() || root[kVersionKey].get<long>() != kParametersFileVersion)
        refuse(source, kVersionKey, "must be " + std::to_string(kParametersFileVersion) + " (the version this Meniscus reads), got " +
                                        shown(root[kVersionKey]));

    ParametersFile file;
    if (root.contains("input")) file.input = text_of(root["input"], source, "input");
    if (root.contains("output")) file.output = text_of(root["output"], source, "output");
    if (root.contains("start")) file.start = frame_of(root["start"], source, "start");
    if (root.contains("end")) file.end = frame_of(root["end"], source, "end");
    if (file.start && file.end)
        if (auto problem = frame_range_problem(*file.start, *file.end)) refuse(source, "end", *problem);
    if (root.contains("interpolate_attributes")) {
        const json& names = root["interpolate_attributes"];
        if (!names.is_array()) refuse(source, "interpolate_attributes", "must be a list of attribute names, got " + shown(names));
        file.attributes.emplace();
        for (const json& name : names) file.attributes->push_back(text_of(name, source, "interpolate_attributes"));
    }
    if (root.contains("parameters")) {
        const json& parameters = root["parameters"];
        if (!parameters.is_object()) refuse(source, "parameters", "must be an object of parameter names and values, got " + shown(parameters));
        std::vector<std::string> names;
        for (const ParameterSpec& spec : parameter_schema()) names.push_back(spec.name);
        for (const auto& item : parameters.items()) {
            const std::string key = "parameters." + item.key();
            if (std::find(names.begin(), names.end(), item.key()) == names.end())
                refuse(source, key, "unknown parameter (the parameters are: " + joined(names) + ")");
            const ParameterSpec& spec = find_parameter(item.key());
            if (spec.is_vector())
                spec.set_vector(file.parameters, schema_vector(spec, item.value(), source, key));
            else
                spec.set(file.parameters, schema_number(spec, item.value(), source, key));
            file.given.push_back(spec.name);
        }
    }
    return file;
}

ParametersFile read_parameters_file(const std::string& path) {
    std::ifstream in(path_from_utf8(path), std::ios::binary);
    if (!in) throw InputError(path + ": cannot read the parameters file");
    std::ostringstream text;
    text << in.rdbuf();
    return parse_parameters_file(text.str(), path);
}

void write_parameters_file(const ParametersFile& file, const std::string& path) {
    std::ofstream out(path_from_utf8(path), std::ios::binary);
    out << parameters_file_text(file);
    if (!out) throw InputError(path + ": cannot write the parameters file");
}

}  // namespace meniscus
