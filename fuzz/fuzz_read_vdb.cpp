// libFuzzer harness: the OpenVDB points reader (formats/vdb_points.cpp, blosc.cpp) on arbitrary bytes (see
// fuzz/README.md). The name is not Mantaflow's, so no config is looked for.
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_vdb_points, "fuzz.vdb")
