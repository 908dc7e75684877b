// VTK XML (.vtu / .vtp): every encoding, pieces, skipped arrays, markup details, unsupported variants and damage.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include "reader_checks.h"

using namespace meniscus;
using namespace meniscus::test;
namespace fs = std::filesystem;

namespace {

std::string vtu(const std::string& pieces, const std::string& root_attributes = "") {
    return "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\"" +
           root_attributes + ">\n<UnstructuredGrid>\n" + pieces + "</UnstructuredGrid>\n</VTKFile>\n";
}

std::string piece(int n, const std::string& points, const std::string& point_data) {
    return "<Piece NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfCells=\"0\">\n<PointData>\n" + point_data +
           "</PointData>\n<Points>\n<DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"ascii\">" + points +
           "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\"></DataArray>\n"
           "</Cells>\n</Piece>\n";
}

}  // namespace

TEST_CASE("every VTK XML encoding variant reads the same 5 particles", "[formats]") {
    int files = 0;
    for (const auto& entry : fs::directory_iterator(kFormats + "/variants")) {
        const std::string ext = entry.path().extension().string();
        if (ext != ".vtu" && ext != ".vtp") continue;
        INFO(entry.path().filename().string());
        require_same(read_particles(entry.path().string()), 5, true, true);
        ++files;
    }
    REQUIRE(files == 26);  // ascii + 3 binary modes x zlib or not x 2 header types x 2 byte orders + PolyData
}

TEST_CASE("VTK XML: pieces, skipped arrays, comments, entities and information keys", "[formats]") {
    TempDir dir("vtu");
    std::string path = dir.file("p.vtu");
    std::string data_a =
        "<!-- a comment with <DataArray> inside -->\n"
        "<DataArray type=\"Float64\" Name=\"rho &amp; co\" format=\"ascii\">\n"
        "  <InformationKey name=\"L2_NORM_RANGE\" location=\"vtkDataArray\" length=\"2\"><Value index=\"0\">99</Value></InformationKey>\n"
        "  1.5 2.5</DataArray>\n"
        "<DataArray type=\"String\" Name=\"label\" format=\"ascii\">102 111 0 98 0</DataArray>\n"
        "<DataArray type=\"Int8\" Name=\"flag\" NumberOfComponents=\"2\" format=\"ascii\"><![CDATA[-1 2]]> 3 4</DataArray>\n";
    std::string data_b =
        "<DataArray type=\"Int8\" Name=\"flag\" NumberOfComponents=\"2\" format=\"ascii\">5 6</DataArray>\n"
        "<DataArray type=\"Float64\" Name=\"rho &amp; co\" format=\"ascii\">3.5</DataArray>\n";
    write_text(path, vtu(piece(2, "0 0 0 1 1 1", data_a) + piece(1, "2 2 2", data_b) + piece(0, "", "")));
    ParticleData p = read_particles(path);
    REQUIRE(p.size() == 3);
    REQUIRE(p.positions == std::vector<float>{0, 0, 0, 1, 1, 1, 2, 2, 2});
    REQUIRE(p.attributes.size() == 2);  // the String array is skipped
    CHECK(p.attributes[0].name == "rho & co");
    CHECK(p.attributes[0].values == std::vector<float>{1.5f, 2.5f, 3.5f});
    CHECK(p.attributes[1].name == "flag");
    CHECK(p.attributes[1].components == 2);
    CHECK(p.attributes[1].values == std::vector<float>{-1, 2, 3, 4, 5, 6});

    // A later piece without one of the first piece's arrays.
    write_text(path, vtu(piece(1, "0 0 0", "<DataArray type=\"Float32\" Name=\"a\" format=\"ascii\">1</DataArray>") +
                         piece(1, "1 1 1", "")));
    require_particle_error(path, "has no point array 'a'");
}

TEST_CASE("VTK XML: unsupported variants are named", "[formats]") {
    TempDir dir("vtu_unsupported");
    std::string path = dir.file("u.vtu");
    write_text(path, vtu(piece(1, "0 0 0", ""), " compressor=\"vtkLZ4DataCompressor\""));
    require_particle_error(path, "compressor 'vtkLZ4DataCompressor'");
    write_text(path, "<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\"><PUnstructuredGrid/></VTKFile>");
    require_particle_error(path, "parallel PUnstructuredGrid");
    write_text(path, "<VTKFile type=\"ImageData\" version=\"1.0\"><ImageData/></VTKFile>");
    require_particle_error(path, "unsupported VTK XML dataset type 'ImageData'");
    write_text(path, vtu(piece(1, "0 0 0", ""), " header_type=\"UInt16\""));
    require_particle_error(path, "header_type 'UInt16'");
    write_text(path, vtu(piece(1, "0 0 0", "<DataArray type=\"Bit\" Name=\"b\" format=\"ascii\">1</DataArray>")));
    require_particle_error(path, "unsupported type 'Bit'");
    write_text(path, "<?xml version=\"1.0\"?>\n<html><body/></html>");
    require_particle_error(path, "not a VTK XML file");
}

TEST_CASE("VTK XML: wrong counts, offsets and sizes", "[formats]") {
    TempDir dir("vtu_bad");
    std::string path = dir.file("b.vtu");
    write_text(path, vtu(piece(3, "0 0 0 1 1 1           ", "")));
    require_particle_error(path, "only 6 of 9 values");
    write_text(path, vtu(piece(3, "0 0 0 1 1 1", "")));
    require_particle_error(path, "9 ASCII values cannot fit in its 11 characters");
    write_text(path, vtu(piece(1, "0 0 0 1 1 1", "")));
    require_particle_error(path, "more than the 3 values");
    write_text(path, vtu(piece(1000000000, "0 0 0", "")));
    require_particle_error(path, "cannot fit in its");
    write_text(path, vtu(piece(1, "0 0 zero", "")));
    require_particle_error(path, "bad value 'zero'");

    // Appended raw data: a size header that disagrees with NumberOfPoints, an offset past the data, shared offsets.
    Bytes raw = read_bytes(kFormats + "/variants/raw_plain_uint32_le.vtu");
    std::string text = as_text(raw);
    std::string bad = text;
    bad.replace(bad.find("NumberOfPoints=\"5\""), 18, "NumberOfPoints=\"6\"");
    write_text(path, bad);
    require_particle_error(path, "Points DataArray holds 60 bytes but 18 values of type Float32 need 72");
    bad = text;
    bad.replace(bad.find("offset=\"24\""), 11, "offset=\"9999999\"");
    write_text(path, bad);
    require_particle_error(path, "beyond the");
    bad = text;
    bad.replace(bad.find("offset=\"24\""), 11, "offset=\"0\"  ");
    write_text(path, bad);
    require_particle_error(path, "same appended offset 0");
    // Cut inside the appended data.
    write_bytes(path, Bytes(raw.begin(), raw.begin() + static_cast<std::ptrdiff_t>(text.find("_") + 30)));
    require_particle_error(path, "");
}

TEST_CASE("VTK XML: corrupt zlib blocks and base64", "[formats]") {
    TempDir dir("vtu_zlib");
    std::string path = dir.file("z.vtu");
    std::string text = as_text(read_bytes(kFormats + "/dam26_zlib_base64.vtu"));
    // Flip a base64 character deep inside the compressed velocity data: zlib notices (or the size does).
    const std::size_t appended = text.find("   _") + 4;
    std::string bad = text;
    std::size_t at = appended + 20000;
    bad[at] = bad[at] == 'A' ? 'B' : 'A';
    write_text(path, bad);
    require_particle_error(path, "DataArray");
    bad = text;
    bad[appended + 10] = '*';
    write_text(path, bad);
    require_particle_error(path, "invalid base64 character '*'");
}
