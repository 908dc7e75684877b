// The bad-input matrix of issue 6: every particle format against empty files, header-only files, truncation at every
// byte, counts larger than the file, negative and huge counts, the wrong byte order, non-finite and extreme
// coordinates, frames too large for memory, directories and unreadable files. Each case ends in a clear error that
// names the file (FormatError from the readers, InputError / ResourceError from the pipeline) or in a documented,
// safe result; nothing crashes or hangs. Sequences (gaps, duplicates, mixed formats) are tested through the CLI in
// tests/python/test_bad_input.py.
#ifndef _WIN32
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#endif

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "io/io.h"
#include "pipeline.h"
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

namespace {

struct SmallFile {
    std::string name;
    // Cuts that leave at least this many bytes short of the end must fail; shorter cuts of text formats can be a
    // complete smaller file (0: no such guarantee, only a clean outcome).
    std::size_t strict_tail;
    bool strict;
};

// How far from its end a file may be cut and still be whole: the closing tags after VTK XML appended data, the
// 0x00 0xff after BGEO points.
std::size_t tail_after_data(const std::string& name, const Bytes& bytes) {
    std::string text(bytes.begin(), bytes.end());
    if (name.size() > 4 && (name.compare(name.size() - 4, 4, ".vtu") == 0 || name.compare(name.size() - 4, 4, ".vtp") == 0)) {
        std::size_t appended = text.rfind("\n  </AppendedData>");
        return appended == std::string::npos ? 1 : bytes.size() - appended;  // inline: only the final newline
    }
    if (name == "binary.bgeo") return 2;
    return 0;
}

ParticleData cloud(std::size_t n, float spacing = 0.05f) {
    ParticleData p;
    for (std::size_t i = 0; i < n; ++i) {
        p.positions.push_back(spacing * static_cast<float>(i % 6));
        p.positions.push_back(spacing * static_cast<float>((i / 6) % 6));
        p.positions.push_back(spacing * static_cast<float>(i / 36));
    }
    return p;
}

PipelineResult reconstruct(const ParticleData& p, double cube = 0.5, std::size_t budget = 0, bool skip_invalid = false) {
    PipelineOptions o;
    o.reconstruction.particle_radius = 0.025;
    o.reconstruction.cube_size = cube;
    o.execution.threads = 2;
    o.execution.memory_budget = static_cast<double>(budget) / (1024.0 * 1024.0 * 1024.0);  // the schema counts in GiB
    o.execution.skip_invalid = skip_invalid;
    return run_pipeline(PositionsView(p.positions.data(), p.size()), {}, o);
}

void require_finite_mesh(const TriMesh& m) {
    std::size_t bad = 0;
    for (float x : m.vertices) bad += !std::isfinite(x);
    REQUIRE(bad == 0);
    for (auto t : m.triangles) REQUIRE((t >= 0 && static_cast<std::size_t>(t) < m.num_vertices()));
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------------
// Files

TEST_CASE("an empty file is refused in every format", "[bad-input]") {
    TempDir dir("empty");
    for (const char* ext : {".vtk", ".vtu", ".vtp", ".bgeo", ".bgeo.gz", ".ply", ".npy", ".npz", ".csv", ".xyz", ".dat"}) {
        std::string path = dir.file(std::string("frame") + ext);
        write_text(path, "");
        require_particle_error(path, "empty file");
    }
}

TEST_CASE("every cut of every small sample gives a clear error or a consistent smaller read", "[bad-input]") {
    TempDir dir("cuts");
    std::size_t files = 0, cuts = 0, errors = 0;
    for (const auto& entry : fs::directory_iterator(kVariants)) {
        const std::string name = entry.path().filename().string();
        const Bytes bytes = read_bytes(entry.path().string());
        const bool text_format = name == "ascii.ply" || name == "text.xyz" || name == "semicolon.csv";
        const bool legacy_vtk = name == "binary.vtk";  // a cut between sections is a complete, smaller file
        const std::size_t tail = tail_after_data(name, bytes);
        ParticleData whole;
        REQUIRE(outcome(entry.path().string(), &whole).empty());
        const std::string path = dir.file(name);  // same name: the extension matters for XYZ
        INFO(name);
        for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
            write_bytes(path, bytes.data(), cut);
            ParticleData p;
            std::string message = outcome(path, &p);
            INFO("cut at " << cut << " of " << bytes.size() << ": " << message);
            ++cuts;
            if (!message.empty()) {
                ++errors;
                REQUIRE(message.rfind(path, 0) == 0);
                continue;
            }
            require_consistent(p);
            REQUIRE(p.size() <= whole.size());
            if (name == "raw.xyz") {
                REQUIRE(cut % 12 == 0);  // whole particles only
                continue;
            }
            if (!text_format && !legacy_vtk) REQUIRE(cut + tail >= bytes.size());
        }
        ++files;
    }
    REQUIRE(files >= 40);
    CHECK(errors > cuts * 9 / 10);
}

TEST_CASE("header-only files", "[bad-input]") {
    TempDir dir("header");
    std::string path = dir.file("h.vtk");
    write_text(path, "# vtk DataFile Version 4.1\nSPlisHSPlasH particle data\nBINARY\nDATASET UNSTRUCTURED_GRID\n");
    require_particle_error(path, "no POINTS section");
    write_text(path, "# vtk DataFile Version 4.1\nSPlisHSPlasH particle data\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS 5 float\n");
    require_particle_error(path, "POINTS count 5 needs 60 bytes");

    path = dir.file("h.vtu");
    write_text(path, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
                     "<UnstructuredGrid>\n");
    require_particle_error(path, "is not closed");
    write_text(path, "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid></UnstructuredGrid></VTKFile>");
    require_particle_error(path, "no <Piece>");
    write_text(path, "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid><Piece NumberOfPoints=\"5\"/></UnstructuredGrid></VTKFile>");
    require_particle_error(path, "has 5 points but no Points DataArray");

    path = dir.file("h.bgeo");
    Bytes bgeo = read_bytes(kVariants + "/binary.bgeo");
    write_bytes(path, bgeo.data(), 41 + 2 + 2 + 6 + 4 + 2 + 8 + 6 + 12);  // counts and both attribute definitions
    require_particle_error(path, "point count 5 (32 bytes per point)");

    path = dir.file("h.ply");
    write_text(path, "ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
                     "property float z\nend_header\n");
    require_particle_error(path, "count 5 needs at least 60 bytes");
    write_text(path, "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
    require_particle_error(path, "count 5 needs at least 30 bytes");
    write_text(path, "ply\nformat ascii 1.0\nelement vertex 5\n");
    require_particle_error(path, "no end_header line");

    path = dir.file("h.npy");
    Bytes npy = read_bytes(kVariants + "/positions.npy");
    write_bytes(path, npy.data(), 128);  // numpy pads the header to 128 bytes
    require_particle_error(path, "array data of shape (5, 3) and dtype '<f4' needs 60 bytes");

    path = dir.file("h.npz");
    Bytes npz = read_bytes(kVariants + "/deflated.npz");
    write_bytes(path, npz.data(), 30 + 13);  // the first local header and its name
    require_particle_error(path, "end-of-central-directory");

    // A CSV header without rows and a VTK XML file with zero points are empty frames, not errors.
    path = dir.file("h.csv");
    write_text(path, "\"Points:0\",\"Points:1\",\"Points:2\"\n");
    REQUIRE(read_particles(path).size() == 0);
}

TEST_CASE("counts larger than the file, negative and huge", "[bad-input]") {
    TempDir dir("counts");
    const std::string vtk_head = "# vtk DataFile Version 4.1\nt\nBINARY\nDATASET POLYDATA\n";
    std::string path = dir.file("c.vtk");
    write_text(path, vtk_head + "POINTS 99999999999 float\n" + std::string(64, 'x'));
    require_particle_error(path, "needs 1199999999988 bytes but the file has only");
    write_text(path, vtk_head + "POINTS -5 float\n" + std::string(64, 'x'));
    require_particle_error(path, "bad POINTS count '-5'");
    write_text(path, vtk_head + "POINTS 18446744073709551615 float\n");
    require_particle_error(path, "impossibly large");

    path = dir.file("c.vtu");
    const Bytes vtu_bytes = read_bytes(kVariants + "/raw_plain_uint32_le.vtu");
    const std::string vtu(vtu_bytes.begin(), vtu_bytes.end());
    auto with_points = [&](const std::string& n) {
        std::string s = vtu;
        s.replace(s.find("NumberOfPoints=\"5\""), 18, "NumberOfPoints=\"" + n + "\"");
        return s;
    };
    write_text(path, with_points("-5"));
    require_particle_error(path, "no valid NumberOfPoints ('-5')");
    write_text(path, with_points("18446744073709551615"));
    require_particle_error(path, "impossibly large");
    write_text(path, with_points("1000000000"));
    require_particle_error(path, "holds 60 bytes but 3000000000 values");
    // The byte-count header of the first array says 4 GiB.
    std::string huge = vtu;
    std::size_t data = huge.find("   _") + 4;
    for (int k = 0; k < 4; ++k) huge[data + static_cast<std::size_t>(k)] = '\xff';
    write_text(path, huge);
    require_particle_error(path, "holds 4294967295 bytes");

    path = dir.file("c.bgeo");
    Bytes bgeo = read_bytes(kVariants + "/binary.bgeo");
    Bytes bad = bgeo;
    bad[9] = 0xff;  // point count -> negative
    write_bytes(path, bad);
    require_particle_error(path, "negative point count");
    bad = bgeo;
    bad[9] = 0x7f;  // point count -> 2^31 - 251
    write_bytes(path, bad);
    require_particle_error(path, "a wrong count");
    bad = bgeo;
    bad[25] = 0x7f;  // attribute count
    write_bytes(path, bad);
    require_particle_error(path, "point attribute count");

    path = dir.file("c.ply");
    write_text(path, "ply\nformat binary_little_endian 1.0\nelement vertex -5\nproperty float x\nend_header\n");
    require_particle_error(path, "bad count '-5'");
    write_text(path, "ply\nformat binary_little_endian 1.0\nelement vertex 99999999999999\nproperty float x\nproperty float y\n"
                     "property float z\nend_header\n" + std::string(12, '\0'));
    require_particle_error(path, "needs at least 1199999999999988 bytes");
    write_text(path, "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                     "property float z\nproperty list uint float extra\nend_header\n" + std::string(12, '\0') + "\xff\xff\xff\xff");
    require_particle_error(path, "list length 4294967295");

    path = dir.file("c.npy");
    Bytes npy = read_bytes(kVariants + "/positions.npy");
    std::string header(npy.begin(), npy.begin() + 128);
    auto with_shape = [&](const std::string& shape) {
        std::string h = header;
        std::size_t at = h.find("(5, 3)");
        h.replace(at, 6, shape);
        h.resize(127, ' ');
        h += '\n';
        Bytes out(h.begin(), h.end());
        out.insert(out.end(), npy.begin() + 128, npy.end());
        return out;
    };
    write_bytes(path, with_shape("(-5, 3)"));
    require_particle_error(path, "not a non-negative integer");
    write_bytes(path, with_shape("(500000000000, 3)"));
    require_particle_error(path, "needs 6000000000000 bytes but the file has only");
    write_bytes(path, with_shape("(9223372036854775807, 3)"));
    require_particle_error(path, "impossibly large");
    write_bytes(path, with_shape("(99999999999999999999, 3)"));
    require_particle_error(path, "bad integer");
    Bytes long_header = npy;
    long_header[8] = 0xff;
    long_header[9] = 0xff;  // header length 65535 > the file
    write_bytes(path, long_header);
    require_particle_error(path, "the .npy header needs 65535 bytes");

    path = dir.file("c.npz");
    Bytes npz = read_bytes(kVariants + "/deflated.npz");
    std::size_t eocd = npz.size() - 22;
    REQUIRE(npz[eocd] == 'P');
    bad = npz;
    bad[eocd + 10] = bad[eocd + 11] = 0xfe;  // 65278 members
    write_bytes(path, bad);
    require_particle_error(path, "claims 65278 members");
    // A member whose central directory claims 2 GiB uncompressed: refused before inflating (or allocating).
    std::size_t central = 0;
    for (std::size_t i = 0; i + 4 < npz.size(); ++i)
        if (npz[i] == 'P' && npz[i + 1] == 'K' && npz[i + 2] == 1 && npz[i + 3] == 2) {
            central = i;
            break;
        }
    REQUIRE(central > 0);
    bad = npz;
    bad[central + 24] = 0;
    bad[central + 25] = 0;
    bad[central + 26] = 0;
    bad[central + 27] = 0x80;
    write_bytes(path, bad);
    require_particle_error(path, "refusing a corrupt file or decompression bomb");
}

TEST_CASE("wrong byte order", "[bad-input]") {
    TempDir dir("endian");
    // Raw XYZ carries no byte order: big-endian data is recognised as byte-swapped and refused.
    std::string path = dir.file("e.xyz");
    Bytes raw = read_bytes(kFormats + "/dam26.xyz");
    for (std::size_t i = 0; i < raw.size(); i += 4) {
        std::swap(raw[i], raw[i + 3]);
        std::swap(raw[i + 1], raw[i + 2]);
    }
    write_bytes(path, raw);
    require_particle_error(path, "byte-swapped");

    // VTK XML: the size header read in the wrong order no longer matches the point count.
    path = dir.file("e.vtu");
    Bytes vtu = read_bytes(kVariants + "/raw_plain_uint32_be.vtu");
    std::string s(vtu.begin(), vtu.end());
    s.replace(s.find("BigEndian"), 9, "LittleEndian");
    write_text(path, s);
    require_particle_error(path, "holds 1006632960 bytes");

    // BGEO is always big-endian: a little-endian header gives impossible counts.
    path = dir.file("e.bgeo");
    Bytes bgeo = read_bytes(kVariants + "/binary.bgeo");
    for (std::size_t i = 5; i < 41; i += 4) {
        std::swap(bgeo[i], bgeo[i + 3]);
        std::swap(bgeo[i + 1], bgeo[i + 2]);
    }
    write_bytes(path, bgeo);
    require_particle_error(path, "");

    // PLY and NumPy declare their byte order; data written in the other order than declared reads as other numbers.
    // Documented: the reader cannot know, the values are kept, and the pipeline's own checks (non-finite
    // coordinates, the grid range, the memory budget) stop what cannot be reconstructed.
    path = dir.file("e.npy");
    Bytes npy = read_bytes(kVariants + "/f4_big_endian.npy");
    std::string h(npy.begin(), npy.end());
    h.replace(h.find("'>f4'"), 5, "'<f4'");
    write_text(path, h);
    ParticleData p;
    REQUIRE(outcome(path, &p).empty());
    REQUIRE(p.size() == 5);
    try {
        require_finite_mesh(reconstruct(p).mesh);
    } catch (const InputError&) {
    } catch (const ResourceError&) {
    }
}

TEST_CASE("NaN and Inf coordinates are read, then refused with a count or dropped", "[bad-input]") {
    TempDir dir("nan");
    std::string path = dir.file("nan.csv");
    std::string text = "x,y,z\n";
    ParticleData c = cloud(100);
    for (std::size_t i = 0; i < c.size(); ++i)
        text += std::to_string(c.positions[3 * i]) + "," + std::to_string(c.positions[3 * i + 1]) + "," + std::to_string(c.positions[3 * i + 2]) + "\n";
    text += "nan,0,0\n0,inf,0\n";
    write_text(path, text);
    ParticleData p = read_particles(path);
    REQUIRE(p.size() == 102);
    REQUIRE(std::isnan(p.positions[300]));
    REQUIRE(std::isinf(p.positions[304]));
    REQUIRE_THROWS_WITH(reconstruct(p), Catch::Contains("2 of 102 particles have NaN or Inf coordinates (the first is particle 100)"));
    REQUIRE_THROWS_AS(reconstruct(p), InputError);
    PipelineResult r = reconstruct(p, 0.5, 0, true);
    REQUIRE(r.mesh.num_triangles() > 0);
    require_finite_mesh(r.mesh);
    bool warned = false;
    for (const auto& w : r.stats.warnings) warned = warned || w.find("dropped 2 particles") != std::string::npos;
    REQUIRE(warned);

    // The same from a binary format: NaN bit patterns survive the readers.
    path = dir.file("nan.npy");
    Bytes npy = read_bytes(kVariants + "/positions.npy");
    const float nan = std::nanf("");
    std::memcpy(&npy[128 + 4], &nan, 4);
    write_bytes(path, npy);
    REQUIRE(std::isnan(read_particles(path).positions[1]));
}

TEST_CASE("degenerate clouds: one point, one particle, 1e30, empty", "[bad-input]") {
    ParticleData same;
    for (int i = 0; i < 100; ++i) same.positions.insert(same.positions.end(), {1.0f, 2.0f, 3.0f});
    PipelineResult r = reconstruct(same);
    REQUIRE(r.mesh.num_triangles() > 0);  // a single drop around the point
    require_finite_mesh(r.mesh);

    ParticleData single;
    single.positions = {0.5f, 0.5f, 0.5f};
    r = reconstruct(single);
    require_finite_mesh(r.mesh);

    ParticleData far = cloud(50);
    far.positions.insert(far.positions.end(), {1e30f, 0.0f, 0.0f});
    REQUIRE_THROWS_AS(reconstruct(far), InputError);
    REQUIRE_THROWS_WITH(reconstruct(far), Catch::Contains("particle 50 has a coordinate too large for the grid"));

    ParticleData shifted = cloud(50);
    for (float& x : shifted.positions) x += 1e30f;
    REQUIRE_THROWS_AS(reconstruct(shifted), InputError);

    ParticleData empty;
    r = reconstruct(empty);
    REQUIRE(r.mesh.num_triangles() == 0);
}

TEST_CASE("a frame too large for memory is refused with the estimate", "[bad-input]") {
    ParticleData frame = read_particles(kShared + "/splashsurf/double_dam_break_frame_26_4732_particles.vtk");
    // A cube size typed 1000 times too small: the estimate, not an attempt.
    try {
        reconstruct(frame, 0.0001);
        FAIL("a 0.0001 r cube size was not refused");
    } catch (const ResourceError& e) {
        INFO(e.what());
        CHECK_THAT(e.what(), Catch::Contains("cube size 0.0001 r"));
        CHECK_THAT(e.what(), Catch::Contains("would need about"));
        CHECK_THAT(e.what(), Catch::Contains("PiB"));
    }
    // An explicit budget is honoured.
    REQUIRE_THROWS_AS(reconstruct(frame, 0.5, 1 << 20), ResourceError);
    REQUIRE_THROWS_WITH(reconstruct(frame, 0.5, 1 << 20), Catch::Contains("more than the memory budget of 1.0 MiB"));
}

TEST_CASE("directories and missing files", "[bad-input]") {
    TempDir dir("paths");
    require_particle_error(dir.path.string(), "is a directory");
    fs::create_directory(dir.file("frames.vtu"));
    require_particle_error(dir.file("frames.vtu"), "is a directory");
    require_particle_error(dir.file("missing.npz"), "cannot open file: No such file or directory");
}

#ifndef _WIN32  // fifos, permission bits and fork are POSIX
TEST_CASE("fifos and unreadable files", "[bad-input]") {
    TempDir dir("special");
    std::string fifo = dir.file("pipe.vtk");
    REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
    require_particle_error(fifo, "is not a regular file");  // refused before opening: reading a fifo could block forever

    // chmod 000. Root reads such files anyway (CAP_DAC_OVERRIDE), so as root the check runs in a child process that
    // has dropped to the unprivileged user "nobody"; without either, it is skipped with a warning.
    std::string locked = dir.file("locked.vtu");
    fs::copy_file(kVariants + "/ascii.vtu", locked);
    REQUIRE(::chmod(locked.c_str(), 0) == 0);
    if (::geteuid() != 0) {
        require_particle_error(locked, "cannot open file: Permission denied");
    } else {
        pid_t child = ::fork();
        REQUIRE(child >= 0);
        if (child == 0) {
            int code = 3;
            if (::setgid(65534) == 0 && ::setuid(65534) == 0) {
                std::string message = outcome(locked);
                code = message.rfind(locked, 0) == 0 && message.find("cannot open file: Permission denied") != std::string::npos ? 0 : 1;
            }
            ::_exit(code);
        }
        int status = 0;
        REQUIRE(::waitpid(child, &status, 0) == child);
        REQUIRE(WIFEXITED(status));
        if (WEXITSTATUS(status) == 3)
            WARN("could not drop privileges to test an unreadable file as root");
        else
            REQUIRE(WEXITSTATUS(status) == 0);
    }

    // A file that no one can read, root included: the kernel fails the read itself.
    if (fs::exists("/proc/self/mem")) {
        std::string message = outcome("/proc/self/mem");
        REQUIRE_THAT(message, Catch::StartsWith("/proc/self/mem: read error"));
    }
}
#endif

// Inputs the fuzzers found (fuzz/README.md): each file is named <harness>-<what>, and must now read cleanly or fail
// with a FormatError. The harness picks the extension (which decides where the content has no magic).
TEST_CASE("fuzzer findings stay fixed", "[bad-input]") {
    TempDir dir("regressions");
    const std::string folder = std::string(MENISCUS_TEST_DATA) + "/fuzz_regressions";
    std::size_t files = 0;
    for (const auto& entry : fs::directory_iterator(folder)) {
        const std::string name = entry.path().filename().string();
        const std::string harness = name.substr(0, name.find('-'));
        INFO(name);
        const Bytes bytes = read_bytes(entry.path().string());
        if (harness == "mesh") {
            std::string path = dir.file("input.obj");
            write_bytes(path, bytes);
            try {
                TriMesh m = read_mesh(path);
                for (auto t : m.triangles) REQUIRE((t >= 0 && static_cast<std::size_t>(t) < m.num_vertices()));
            } catch (const FormatError& e) {
                REQUIRE(std::string(e.what()).rfind(path, 0) == 0);
            }
        } else {
            std::string path = dir.file("input." + (harness == "particles" ? std::string("bin") : harness));
            write_bytes(path, bytes);
            ParticleData p;
            std::string message = outcome(path, &p);
            INFO(message);
            if (message.empty())
                require_consistent(p);
            else
                REQUIRE(message.rfind(path, 0) == 0);
        }
        ++files;
    }
    REQUIRE(files >= 1);
}
