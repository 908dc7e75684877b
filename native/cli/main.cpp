// The `meniscus` executable: the command line of cli.h with the process's UTF-8 arguments.
#include "cli.h"
#include "base/platform.h"

int main(int argc, char** argv) {
    meniscus::use_utf8_console();
    return meniscus::run_cli(meniscus::utf8_arguments(argc, argv));
}
