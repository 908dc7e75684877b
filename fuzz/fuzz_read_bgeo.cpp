// libFuzzer harness: the bgeo particle reader on arbitrary bytes (see fuzz/README.md).
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_bgeo_particles, "fuzz.bgeo")
