// libFuzzer harness: the npz particle reader on arbitrary bytes (see fuzz/README.md).
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_npz_particles, "fuzz.npz")
