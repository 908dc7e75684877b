// libFuzzer harness: the xyz particle reader on arbitrary bytes (see fuzz/README.md).
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_xyz_particles, "fuzz.xyz")
