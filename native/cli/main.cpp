// The `meniscus` executable: the command line of cli.h with the process's UTF-8 arguments.
#include <cstdlib>

#include "base/platform.h"
#include "base/waiting.h"
#include "cli.h"

#if defined(__linux__) && defined(MENISCUS_LIBGOMP)
#include <unistd.h>
#endif

namespace {

// GNU libgomp reads its wait policy only when it loads, before main(): when the user chose none, the process sets a
// short spin (base/waiting.h) and starts itself again, once (the variable is then set). Only where /proc/self/exe
// names this program (Linux); elsewhere, and if the exec fails, it runs on with the runtime's default.
void wait_briefly_at_barriers(char** argv) {
#if defined(__linux__) && defined(MENISCUS_LIBGOMP)
    if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT")) return;
    // The program's own file by its real name (exec'ing /proc/self/exe itself would name the process "exe").
    char self[4096];
    const ssize_t length = readlink("/proc/self/exe", self, sizeof self - 1);
    if (length <= 0 || static_cast<std::size_t>(length) >= sizeof self - 1) return;
    self[length] = '\0';
    if (setenv("GOMP_SPINCOUNT", meniscus::kBarrierSpinCount, 1) != 0) return;
    execv(self, argv);
    unsetenv("GOMP_SPINCOUNT");  // not this process's policy: keep children as they were
#else
    (void)argv;
    meniscus::wait_briefly_at_barriers();
#endif
}

}  // namespace

int main(int argc, char** argv) {
    wait_briefly_at_barriers(argv);
    meniscus::use_utf8_console();
    return meniscus::run_cli(meniscus::utf8_arguments(argc, argv));
}
