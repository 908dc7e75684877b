// Writers' temporary files (native/core/io/partial_files.h): their names carry the writer's process id, and a later
// writer removes those whose process is gone once they are old enough, never a live writer's or any other file.
#include <catch2/catch.hpp>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "base/platform.h"
#include "io/partial_files.h"
#include "test_files.h"

using namespace meniscus;
namespace fs = std::filesystem;

namespace {
// Above every process id Linux (at most 2^22) and Windows hand out: no such process.
constexpr long kNoSuchProcess = 999999999;
}  // namespace

TEST_CASE("a temporary file's name gives its writer's process id", "[partial]") {
    CHECK(partial_writer(".partial-4711-surface_0023.ply") == 4711);
    CHECK(partial_writer("fluid_0023.partial4711.npz") == 4711);
    CHECK(partial_writer("fluid_0023.npz.partial4711.meniscus") == 4711);
    for (const char* other : {"fluid_0023.npz", "fluid_partial.npz", "fluid_0023.partial.npz", "fluid.partial12a.npz",
                              ".partial12.npz", ".partial-x-a.ply", ".partial-12-", "fluid.partial12.tar.gz",
                              "fluid.partial12345678901.npz", "notes.partial7"})
        CHECK(partial_writer(other) == -1);
    const std::string path = partial_path(path_to_utf8(fs::path("cache") / "fluid_0023.npz"), 42);
    CHECK(path == path_to_utf8(fs::path("cache") / "fluid_0023.partial42.npz"));
    CHECK(partial_writer(path_to_utf8(path_from_utf8(path).filename())) == 42);
    CHECK(partial_writer(path_to_utf8(path_from_utf8(partial_path("fluid_0023.npz.meniscus", 42)).filename())) == 42);
    const std::string hidden = hidden_partial_path(path_to_utf8(fs::path("out") / "surface_0023.ply"), 42);
    CHECK(hidden == path_to_utf8(fs::path("out") / ".partial-42-surface_0023.ply"));
    CHECK(partial_writer(path_to_utf8(path_from_utf8(hidden).filename())) == 42);
}

TEST_CASE("this process exists and an impossible process id does not", "[partial][platform]") {
    CHECK(process_exists(current_process_id()));
    CHECK_FALSE(process_exists(kNoSuchProcess));
    CHECK_FALSE(process_exists(0));
    CHECK_FALSE(process_exists(-5));
}

TEST_CASE("only abandoned temporary files of gone writers are removed", "[partial]") {
    test::TempDir folder("partials");
    const std::string dead = std::to_string(kNoSuchProcess), live = std::to_string(current_process_id());
    const std::vector<std::string> abandoned = {"fluid_0023.partial" + dead + ".npz", ".partial-" + dead + "-surface_0023.ply",
                                                "fluid_0023.npz.partial" + dead + ".meniscus"};
    const std::vector<std::string> kept_old = {"fluid_0024.partial" + live + ".npz", "fluid_0025.npz", "fluid_partial.npz",
                                               ".partial-" + live + "-surface_0024.ply"};
    const std::string recent = "fluid_0026.partial" + dead + ".npz";  // perhaps another machine's writer, at work
    const auto old = fs::file_time_type::clock::now() - std::chrono::seconds(static_cast<long>(kAbandonedPartialSeconds) + 60);
    for (const std::vector<std::string>* names : {&abandoned, &kept_old})
        for (const std::string& name : *names) {
            test::write_text(folder.file(name), "x");
            fs::last_write_time(folder.path / name, old);
        }
    test::write_text(folder.file(recent), "x");
    fs::create_directories(folder.path / ("sub.partial" + dead + ".d"));  // a folder is never removed
    std::error_code unsupported;  // Wine refuses to set a folder's time: the folder is then merely recent
    fs::last_write_time(folder.path / ("sub.partial" + dead + ".d"), old, unsupported);

    std::vector<std::string> removed = remove_abandoned_partials(path_to_utf8(folder.path));
    std::sort(removed.begin(), removed.end());
    std::vector<std::string> expected = abandoned;
    std::sort(expected.begin(), expected.end());
    CHECK(removed == expected);
    for (const std::string& name : abandoned) CHECK_FALSE(fs::exists(folder.path / name));
    for (const std::string& name : kept_old) CHECK(fs::exists(folder.path / name));
    CHECK(fs::exists(folder.path / recent));
    CHECK(fs::is_directory(folder.path / ("sub.partial" + dead + ".d")));
    CHECK(remove_abandoned_partials(path_to_utf8(folder.path / "no such folder")).empty());
}
