// libFuzzer harness: the vtk particle reader on arbitrary bytes (see fuzz/README.md).
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_vtk_particles, "fuzz.vtk")
