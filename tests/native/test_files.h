// Temporary directories and byte-level file helpers shared by the reader tests.
#pragma once
#include <zlib.h>
#ifdef _WIN32
#include <process.h>
#else
#include <unistd.h>
#endif

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace meniscus {
namespace test {

namespace fs = std::filesystem;
using Bytes = std::vector<unsigned char>;

// The damage tests rewrite thousands of files; on some disks (ext4 with online discard) each truncation costs
// milliseconds, so a RAM-backed /dev/shm is preferred unless TMPDIR asks for a specific place.
inline fs::path temp_root() {
#ifndef _WIN32
    std::error_code ec;
    if (!std::getenv("TMPDIR") && fs::is_directory("/dev/shm", ec) && ::access("/dev/shm", W_OK) == 0) return "/dev/shm";
#endif
    return fs::temp_directory_path();
}

inline int process_id() {
#ifdef _WIN32
    return _getpid();
#else
    return static_cast<int>(::getpid());
#endif
}

// A fresh directory under the temp root, readable by other users (the unreadable-file tests drop to 'nobody'),
// removed at the end of the test.
struct TempDir {
    fs::path path;
    explicit TempDir(const std::string& tag) {
        static int counter = 0;
        path = temp_root() / ("meniscus_test_" + std::to_string(process_id()) + "_" + tag + "_" + std::to_string(counter++));
        remove(path);
        fs::create_directories(path);
        fs::permissions(path, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec | fs::perms::others_read |
                                  fs::perms::others_exec);
    }
    ~TempDir() { remove(path); }
    // Windows refuses to delete read-only files (copies of the read-only shared frames are): make them writable.
    static void remove(const fs::path& folder) {
        std::error_code ec;
        if (!fs::exists(folder, ec)) return;
        for (const auto& entry : fs::recursive_directory_iterator(folder, ec))
            fs::permissions(entry.path(), fs::perms::owner_write, fs::perm_options::add, ec);
        fs::remove_all(folder, ec);
    }
    std::string file(const std::string& name) const { return (path / name).string(); }
};

// One read of the whole file: byte by byte through istreambuf_iterator took most of a test's time in the sanitizer
// build, whose suite is compiled with little inlining (-Og).
inline Bytes read_bytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    const std::streamoff size = in ? static_cast<std::streamoff>(in.tellg()) : 0;
    Bytes bytes(static_cast<std::size_t>(size > 0 ? size : 0));
    in.seekg(0);
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    bytes.resize(static_cast<std::size_t>(in.gcount()));
    return bytes;
}
inline void write_bytes(const std::string& path, const unsigned char* data, std::size_t size) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}
inline void write_bytes(const std::string& path, const Bytes& bytes, std::size_t length) { write_bytes(path, bytes.data(), length); }
inline void write_bytes(const std::string& path, const Bytes& bytes) { write_bytes(path, bytes.data(), bytes.size()); }
inline void write_text(const std::string& path, const std::string& text) {
    write_bytes(path, reinterpret_cast<const unsigned char*>(text.data()), text.size());
}

// Compresses with zlib: window_bits 15 + 16 gives a gzip file, -15 raw deflate data (as in zip archives).
inline Bytes deflate_bytes(const Bytes& data, int window_bits) {
    z_stream zs{};
    REQUIRE(deflateInit2(&zs, Z_DEFAULT_COMPRESSION, Z_DEFLATED, window_bits, 8, Z_DEFAULT_STRATEGY) == Z_OK);
    Bytes out(deflateBound(&zs, static_cast<uLong>(data.size())) + 64);
    zs.next_in = const_cast<Bytef*>(data.data());
    zs.avail_in = static_cast<uInt>(data.size());
    zs.next_out = out.data();
    zs.avail_out = static_cast<uInt>(out.size());
    REQUIRE(deflate(&zs, Z_FINISH) == Z_STREAM_END);
    out.resize(zs.total_out);
    deflateEnd(&zs);
    return out;
}

inline Bytes gzip(const Bytes& data) { return deflate_bytes(data, 15 + 16); }

}  // namespace test
}  // namespace meniscus
