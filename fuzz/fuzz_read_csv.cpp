// libFuzzer harness: the csv particle reader on arbitrary bytes (see fuzz/README.md).
#include "fuzz_common.h"

MENISCUS_FUZZ_READER(read_csv_particles, "fuzz.csv")
