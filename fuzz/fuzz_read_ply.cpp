// libFuzzer harness: the ply particle reader on arbitrary bytes (see fuzz/README.md).
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_ply_particles, "fuzz.ply")
