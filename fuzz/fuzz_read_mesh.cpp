// libFuzzer harness: read_mesh on arbitrary bytes. PLY and legacy VTK are recognised by their headers whatever the
// name, so naming the input .obj reaches the PLY, the VTK and the OBJ reader.
#include "fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    return meniscus_fuzz::run(data, size, "fuzz.obj", [](const meniscus::io_detail::Source& s) {
        return meniscus::io_detail::read_mesh_from_bytes(s.path, meniscus::io_detail::Bytes(s.data, s.data + s.size));
    });
}
