// Mantaflow's cache files as Blender's fluid simulation writes them (layout in docs/formats.md): the parsers of the
// single files, and the world placement from the cache's config/config_####.uni. Internal to the readers and the
// fuzz harnesses.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "io/io_util.h"
#include "sph/fluid_domain.h"

namespace meniscus {
namespace io_detail {

// A PB02 particle system (pp_####.uni, ppSnd_####.uni): positions in grid index space (cell corners at integers)
// and Mantaflow's particle flags, one per particle.
struct MantaflowParticleSystem {
    std::array<int, 3> grid{0, 0, 0};
    std::vector<float> positions;  // 3 per particle
    std::vector<std::int32_t> flags;
};
MantaflowParticleSystem parse_mantaflow_particle_system(const Source& source);

// A PD01 particle data file of 3-vectors (pVel_####.uni) with `count` elements on the same grid.
std::vector<float> parse_mantaflow_vec3_data(const Source& source, std::size_t count, const std::array<int, 3>& grid);

// config/config_####.uni: the domain's settings at that frame, as Blender's MANTA::writeConfiguration writes them.
struct MantaflowConfig {
    std::array<int, 3> resolution{0, 0, 0};  // the grid the files of this frame use
    float dx = 0.0f;                         // 1 / the domain's resolution setting (cells along the longest side)
    float frame_length = 0.0f;               // Mantaflow time units of the last step
    std::array<float, 3> p0{}, p1{};         // the domain mesh's bounds in object space
    std::array<float, 16> object_to_world{}; // the domain object's matrix, column-major (Blender's obmat)
    std::array<int, 3> base_resolution{0, 0, 0}, res_min{0, 0, 0}, res_max{0, 0, 0};
};
MantaflowConfig parse_mantaflow_config(const Source& source);

// Where Blender shows the grid: grid index g lies at object-space centre + (g - resolution/2) * cell / |scale|,
// then the domain object's matrix; cells are cubes of the longest world side / the longest resolution. The
// Mantaflow mesh (normalised to a unit box around 0) and the particles both land where Blender draws them.
FluidDomain fluid_domain_from_config(const MantaflowConfig& config, const std::string& config_path);

// A bobj mesh (Mantaflow's own surface, mesh/fluid_mesh_####.bobj.gz, already gunzipped): vertices in Mantaflow's
// normalised space (grid / longest resolution, centred on 0), unchanged.
TriMesh parse_mantaflow_bobj(const Source& source);

// The readers behind read_particles / read_mesh: they parse the file and place it in the world with its cache's
// config (required: without it the grid has no place in the world). The particle reader adds the sibling
// pVel_####.uni as `velocity` in m/s when it exists.
ParticleData read_mantaflow_uni_particles(const Source& source);
// OpenVDB points (read_vdb_points); a Mantaflow data cache file (data/fluid_data_####.vdb) is placed in the world
// by its config like the UNI particles, its particles_velocity becoming `velocity` in m/s. Other files (Houdini)
// keep the VDB's world space and attribute names.
ParticleData read_vdb_particles(const Source& source);
TriMesh read_mantaflow_bobj_mesh(const Source& source);

}  // namespace io_detail
}  // namespace meniscus
