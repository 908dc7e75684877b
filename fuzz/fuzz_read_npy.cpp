// libFuzzer harness: the npy particle reader on arbitrary bytes (see fuzz/README.md).
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_npy_particles, "fuzz.npy")
