// The parameters file (native/cli/parameters_file.h): every schema parameter written and read back, and the keys of
// refused values named.
#include <catch2/catch.hpp>

#include <cmath>

#include "base/errors.h"
#include "parameters_file.h"

using namespace meniscus;

namespace {
// An allowed value of a number parameter other than its default.
double other_value(const ParameterSpec& spec) {
    const double current = spec.default_value();
    for (double candidate : {spec.suggested, spec.soft_maximum, spec.soft_minimum, current + 1.0, current * 0.5})
        if (candidate != current && !spec.problem(candidate) && (spec.type != ParameterType::count || candidate == std::floor(candidate)))
            return candidate;
    FAIL("no other value for " << spec.name);
    return current;
}
}  // namespace

TEST_CASE("a parameters file round-trips every schema parameter", "[parameters-file]") {
    ParametersFile file;
    for (const ParameterSpec& spec : parameter_schema()) {
        if (spec.is_vector())
            spec.set_vector(file.parameters, Vector3{spec.name.find("_min") != std::string::npos ? -1.0 : 2.0, 0.5, 3.25});
        else
            spec.set(file.parameters, spec.type == ParameterType::flag ? 1.0 - spec.default_value() : other_value(spec));
    }
    file.input = "in/fluid_{}.vtk";
    file.output = "out/surface_####.ply";
    file.start = -2;
    file.end = 240;
    file.attributes = std::vector<std::string>{"velocity", "id"};
    const std::string text = parameters_file_text(file);
    const ParametersFile read = parse_parameters_file(text, "job.json");
    for (const ParameterSpec& spec : parameter_schema()) {
        INFO(spec.name);
        if (spec.is_vector())
            CHECK(spec.get_vector(read.parameters) == spec.get_vector(file.parameters));
        else
            CHECK(spec.get(read.parameters) == spec.get(file.parameters));
    }
    CHECK(read.given.size() == parameter_schema().size());
    CHECK((read.input == file.input && read.output == file.output && read.start == file.start && read.end == file.end));
    CHECK(read.attributes == file.attributes);
    CHECK(parameters_file_text(read) == text);
}

TEST_CASE("a parameters file keeps the defaults of what it leaves out", "[parameters-file]") {
    const ParametersFile read = parse_parameters_file(R"({"meniscus_parameters": 1, "parameters": {"particle_radius": 0.03}})", "f");
    CHECK(read.parameters.reconstruction.particle_radius == 0.03);
    CHECK(read.parameters.reconstruction.cube_size == Parameters{}.reconstruction.cube_size);
    CHECK(read.given == std::vector<std::string>{"particle_radius"});
    CHECK((!read.input && !read.start && !read.attributes));
}

TEST_CASE("refusals of a parameters file name the key", "[parameters-file]") {
    const auto refusal = [](const std::string& text) {
        try {
            parse_parameters_file(text, "job.json");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("accepted");
    };
    CHECK(refusal(R"({"meniscus_parameters": 1, "parameters": {"cube_size": 0}})") ==
          "job.json: parameters.cube_size: must be a number greater than 0, got 0");
    CHECK_THAT(refusal(R"({"meniscus_parameters": 1, "parameters": {"cube_sise": 1}})"),
               Catch::Contains("job.json: parameters.cube_sise: unknown parameter"));
    CHECK_THAT(refusal(R"({"meniscus_parameters": 1, "parameters": {"normals": "on"}})"),
               Catch::Contains("parameters.normals: must be true or false, got \"on\""));
    CHECK_THAT(refusal(R"({"meniscus_parameters": 1, "parameters": {"smoothing_iterations": 2.5}})"),
               Catch::Contains("parameters.smoothing_iterations: must be a whole number"));
    CHECK_THAT(refusal(R"({"meniscus_parameters": 1, "parameters": {"mesh_aabb_min": [1, 2]}})"),
               Catch::Contains("parameters.mesh_aabb_min: must be three numbers"));
    CHECK_THAT(refusal(R"({"meniscus_parameters": 1, "end": 2.5})"), Catch::Contains("job.json: end: must be a whole frame number"));
    CHECK_THAT(refusal(R"({"meniscus_parameters": 1, "frames": "1-3"})"), Catch::Contains("job.json: frames: unknown key"));
    CHECK_THAT(refusal(R"({"meniscus_parameters": 2})"), Catch::Contains("meniscus_parameters: must be 1"));
    CHECK_THAT(refusal(R"({"parameters": {}})"), Catch::Contains("meniscus_parameters: missing"));
    CHECK_THAT(refusal("[1, 2]"), Catch::Contains("a parameters file is a JSON object"));
    CHECK_THAT(refusal("{\"meniscus"), Catch::Contains("job.json: not a JSON parameters file"));
}
