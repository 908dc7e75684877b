// libFuzzer harness: the Mantaflow cache parsers (formats/mantaflow.cpp) on arbitrary bytes. The readers behind
// read_particles / read_mesh also open sibling files (the config, pVel), so each file parser is fed directly: the
// PB02 particle system, PD01 vectors (count and grid taken from the input's own header, so the payload is reached),
// the config with the world placement made from it, and the bobj mesh.
#include <array>
#include <cstring>

#include "fuzz_common.h"
#include "io/formats/mantaflow.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    using namespace meniscus::io_detail;
    const Source source{"fuzz.uni", data, size, false};
    try {
        const MantaflowParticleSystem system = parse_mantaflow_particle_system(source);
        if (system.positions.size() != 3 * system.flags.size()) std::abort();
    } catch (const meniscus::FormatError&) {
    }
    try {
        std::int32_t header[4] = {0, 0, 0, 0};
        if (size >= 20) std::memcpy(header, data + 4, sizeof header);
        const std::size_t count = header[0] > 0 ? static_cast<std::size_t>(header[0]) : 0;
        const std::vector<float> values = parse_mantaflow_vec3_data(source, count, {header[1], header[2], header[3]});
        if (values.size() != 3 * count) std::abort();
    } catch (const meniscus::FormatError&) {
    }
    try {
        fluid_domain_from_config(parse_mantaflow_config(source), source.path);
    } catch (const meniscus::FormatError&) {
    }
    try {
        meniscus_fuzz::check(parse_mantaflow_bobj(source));
    } catch (const meniscus::FormatError&) {
    }
    return 0;
}
