// libFuzzer harness: the Houdini JSON geometry reader (ASCII .geo and binary .bgeo) on arbitrary bytes.
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_houdini_json_particles, "fuzz.bgeo")
