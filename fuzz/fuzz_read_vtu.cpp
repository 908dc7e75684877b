// libFuzzer harness: the vtu particle reader on arbitrary bytes (see fuzz/README.md).
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_vtu_particles, "fuzz.vtu")
