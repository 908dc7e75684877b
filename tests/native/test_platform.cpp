// The portable layer (native/core/base): memory queries, UTF-8 paths and locale-independent decimal text. These run
// in every build: Linux (GCC), Windows (mingw-w64 under Wine) and clang with libc++ (macOS's library).
#include <catch2/catch.hpp>
#include <atomic>
#include <chrono>
#include <thread>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "base/decimal.h"
#include "base/machine_load.h"
#include "base/memory.h"
#include "base/parallel.h"
#include "base/platform.h"

using namespace meniscus;

TEST_CASE("physical memory and peak memory are read from the operating system", "[platform]") {
    const std::size_t physical = physical_memory_bytes();
    REQUIRE(physical >= (std::size_t(256) << 20));  // every machine that runs this has more than 256 MiB
    REQUIRE(physical <= (std::size_t(1) << 50));
    const std::size_t before = peak_rss_bytes();
    REQUIRE(before > 0);
    // Touch 64 MiB more than the peak so far: the peak must rise by most of it.
    std::vector<unsigned char> block(before + (std::size_t(64) << 20));
    for (std::size_t i = 0; i < block.size(); i += 4096) block[i] = static_cast<unsigned char>(i);
    const std::size_t after = peak_rss_bytes();
    REQUIRE(after >= before + (std::size_t(48) << 20));
    REQUIRE(block[4096] == static_cast<unsigned char>(4096));
}

TEST_CASE("UTF-8 paths survive the round trip through the platform's path type", "[platform]") {
    const std::string name = "fl\xc3\xbcssigkeit \xe7\xb2\x92\xe5\xad\x90/frame_0001.vtk";  // "flüssigkeit 粒子/..."
    const auto path = path_from_utf8(name);
    REQUIRE(path_to_utf8(path) == name);
    REQUIRE(path_to_utf8(path.filename()) == "frame_0001.vtk");
    REQUIRE(path_to_utf8(path.parent_path()) == "fl\xc3\xbcssigkeit \xe7\xb2\x92\xe5\xad\x90");
    std::FILE* missing = open_file(name, "rb");
    REQUIRE(missing == nullptr);
}

TEST_CASE("a file being read is replaced in one step, and the reader keeps the old contents", "[platform]") {
    // On Windows a rename over an open file fails unless its reader shares delete access: the core's readers do.
    const std::filesystem::path folder = std::filesystem::temp_directory_path() / path_from_utf8("meniscus replace \xc3\xa9");
    std::filesystem::create_directories(folder);
    const std::string target = path_to_utf8(folder / "mesh.ply"), partial = path_to_utf8(folder / ".partial-mesh.ply");
    auto write = [](const std::string& path, const char* text) {
        std::FILE* file = open_file(path, "wb");
        REQUIRE(file);
        std::fputs(text, file);
        std::fclose(file);
    };
    write(target, "old");
    write(partial, "new");
    std::FILE* reader = open_file(target, "rb");
    REQUIRE(reader);
    CHECK(replace_file(partial, target).empty());
    char text[8] = {};
    CHECK(std::fread(text, 1, 3, reader) == 3);
    CHECK(std::string(text) == "old");
    std::fclose(reader);
    reader = open_file(target, "rb");
    REQUIRE(reader);
    CHECK(std::fread(text, 1, 3, reader) == 3);
    CHECK(std::string(text) == "new");
    std::fclose(reader);
    CHECK_FALSE(replace_file(partial, target).empty());  // nothing left to move: the reason, not a crash
    std::filesystem::remove_all(folder);
}

TEST_CASE("decimal text reads back every float exactly", "[platform]") {
    std::mt19937 random(42);
    char text[40];
    for (int i = 0; i < 200000; ++i) {
        std::uint32_t bits = random();
        float value;
        std::memcpy(&value, &bits, 4);
        if (!std::isfinite(value)) continue;
        char* end = format_decimal(text, value);
        REQUIRE(end > text);
        REQUIRE(end - text <= 32);
        float back = 0;
        const DecimalResult r = parse_decimal(text, end, back);
        REQUIRE(r.error == std::errc());
        REQUIRE(r.end == end);
        REQUIRE(back == value);
    }
    for (float value : {0.0f, 1.0f, 0.1f, -2.5f, 1e-45f, 3.4028235e38f, 0.025f}) {
        char* end = format_decimal(text, value);
        REQUIRE(std::string(text, end).find(',') == std::string::npos);
        float back = 0;
        REQUIRE(parse_decimal(text, end, back).error == std::errc());
        REQUIRE(back == value);
    }
}

TEST_CASE("decimal parsing follows std::from_chars on every library", "[platform]") {
    auto parse = [](const std::string& s, double& out) { return parse_decimal(s.data(), s.data() + s.size(), out); };
    double d = 0;
    REQUIRE(parse("2.5e3", d).error == std::errc());
    REQUIRE(d == 2500.0);
    REQUIRE(parse("-0.125", d).error == std::errc());
    REQUIRE(d == -0.125);
    REQUIRE(parse("inf", d).error == std::errc());
    REQUIRE(std::isinf(d));
    REQUIRE(parse("nan", d).error == std::errc());
    REQUIRE(std::isnan(d));
    REQUIRE(parse(" 1", d).error == std::errc::invalid_argument);  // no leading blanks
    REQUIRE(parse("+1", d).error == std::errc::invalid_argument);  // no '+' (the readers strip it themselves)
    REQUIRE(parse("abc", d).error == std::errc::invalid_argument);
    const std::string hex = "0x10";
    REQUIRE(parse(hex, d).end == hex.data() + 1);  // hexadecimal is not the general format: only the 0 is read
    const std::string partial = "1.5,7";
    REQUIRE(parse(partial, d).end == partial.data() + 3);  // a decimal comma ends the number, whatever the locale
    REQUIRE(d == 1.5);
    float f = 7;
    const std::string too_big = "1e50";
    REQUIRE(parse_decimal(too_big.data(), too_big.data() + too_big.size(), f).error == std::errc::result_out_of_range);
}

TEST_CASE("the automatic thread count leaves the cores that other programs hold", "[platform]") {
    REQUIRE(free_cores(2, 2, 2, 0) == 2);    // an idle 2-core machine: both
    REQUIRE(free_cores(2, 2, 2, 2) == 1);    // two busy loops: one thread, never none
    REQUIRE(free_cores(2, 2, 2, 1) == 1);
    REQUIRE(free_cores(16, 16, 16, 2) == 14);
    REQUIRE(free_cores(4, 16, 16, 2) == 4);  // a smaller count asked for (OMP_NUM_THREADS) stays the most
    REQUIRE(free_cores(2, 2, 16, 2) == 2);   // pinned to 2 of 16 cores: two threads elsewhere fall mostly elsewhere
    REQUIRE(free_cores(2, 2, 16, 16) == 1);
    REQUIRE(free_cores(0, 0, 0, 0) == 1);
    const int taken = automatic_frame_threads();
    REQUIRE(taken >= 1);
    REQUIRE(taken <= resolve_threads(0));
}

#ifdef __linux__
TEST_CASE("this process's own busy threads are told apart from other programs'", "[platform]") {
    // Three threads spinning here are running or ready to run whatever the machine's load: with the caller, at least
    // four of this process's own. They are in /proc/loadavg's count too, and must not take a frame's cores away.
    std::atomic<bool> stop{false};
    std::vector<std::thread> spinners;
    for (int i = 0; i < 3; ++i)
        spinners.emplace_back([&stop] {
            while (!stop.load(std::memory_order_relaxed)) {
            }
        });
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const int own = own_running_threads();
    stop = true;
    for (std::thread& spinner : spinners) spinner.join();
    CHECK(own >= 4);
    CHECK(own_running_threads() >= 1);  // the caller
}
#endif
