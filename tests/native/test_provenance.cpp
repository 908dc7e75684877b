// Provenance records (native/core/io/provenance.h): a mesh's record matches the parameters and particle file it was
// made from, and a mismatch names what changed; what does not shape the mesh changes nothing.
#include <catch2/catch.hpp>

#include "base/errors.h"
#include "io/provenance.h"
#include "test_files.h"

using namespace meniscus;
using namespace meniscus::test;

TEST_CASE("a provenance record names what changed since the mesh was made", "[provenance]") {
    TempDir dir("provenance");
    const std::string source = dir.file("fluid_0001.vtk"), mesh = dir.file("surface_0001.ply");
    write_text(source, "particles");
    write_text(mesh, "mesh");
    Parameters made;
    made.reconstruction.particle_radius = 0.025;
    const std::string record = provenance_record(made, {"velocity"}, source);

    CHECK(provenance_mismatch(mesh, record) == "no record of what it was made from");
    write_provenance(mesh, record);
    CHECK(provenance_mismatch(mesh, record).empty());

    Parameters now = made;
    now.execution.threads = 3;                        // how, not what
    now.postprocess.quad_max_normal_angle = 20.0;     // takes no part without quads
    now.reconstruction.particle_radius = 0.025000000372529;  // the same float (Blender stores floats)
    CHECK(provenance_mismatch(mesh, provenance_record(now, {"velocity"}, source)).empty());
    now.reconstruction.particle_radius = 0.03;
    CHECK(provenance_mismatch(mesh, provenance_record(now, {"velocity"}, source)) ==
          "made with particle_radius 0.025, now 0.03");
    CHECK(provenance_mismatch(mesh, provenance_record(made, {}, source)) ==
          "made with interpolated attributes velocity, now none");
    // The parameters alone (the particle file is gone).
    CHECK(provenance_mismatch(mesh, provenance_record(made, {"velocity"}, "")).empty());

    write_text(source, "other particles");  // another size
    CHECK(provenance_mismatch(mesh, provenance_record(made, {"velocity"}, source)) ==
          "its particle file fluid_0001.vtk changed since (size or modification time)");

    forget_provenance(mesh);
    CHECK(provenance_mismatch(mesh, record) == "no record of what it was made from");
    CHECK_THROWS_AS(provenance_record(made, {}, dir.file("missing.vtk")), FormatError);
}
