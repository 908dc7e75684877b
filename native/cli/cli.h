// The meniscus command line as a function, shared by the `meniscus` executable and the Python module (whose
// console script gives pip users the same tool without a compiler).
#pragma once
#include <functional>
#include <string>
#include <vector>

namespace meniscus {

struct CliHooks {
    // Asked between frames of a sequence; true stops the run (Ctrl-C in Python, which cannot interrupt native code).
    std::function<bool()> interrupted;
};

// Exit status of a run stopped by CliHooks::interrupted (128 + SIGINT, as shells report Ctrl-C).
inline constexpr int kExitInterrupted = 130;

// Runs the command line; arguments[0] is the program name, all UTF-8. Returns the process exit status:
// 0 success, 1 a frame failed (the others still ran), 2 bad usage or input, 130 interrupted.
int run_cli(const std::vector<std::string>& arguments, const CliHooks& hooks = {});

}  // namespace meniscus
