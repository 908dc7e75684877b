// Mantaflow's cache files (Blender's fluid simulation): UNI particle systems (PB02) with their PD01 velocities,
// the per-frame config that places the grid in the world, and bobj meshes. Byte layouts in docs/formats.md.
#include "io/formats/mantaflow.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <system_error>

#include "base/platform.h"

namespace meniscus {
namespace io_detail {

namespace {

// Mantaflow's particle flags (ParticleBase::ParticleStatus): particles marked for deletion or invalid are not
// part of the liquid any more.
constexpr std::int32_t kParticleDeleted = 1 << 10;
constexpr std::int32_t kParticleInvalid = 1 << 30;

// Mantaflow's velocities are grid cells per Mantaflow time unit; Blender's fluid scripts give one second
// 0.1 * 25 = 2.5 time units (frameLengthRaw), whatever the frame rate.
constexpr double kMantaflowTimeUnitsPerSecond = 2.5;

constexpr std::size_t kConfigBytes = 204;
constexpr int kMaxGridCells = 1 << 16;  // per axis; far beyond any domain Blender can bake

struct UniHeader {
    std::int32_t count = 0;
    std::array<int, 3> grid{0, 0, 0};
    std::int32_t element_type = 0, element_bytes = 0;
};

std::int32_t le_i32(Cursor& c, const char* what) { return static_cast<std::int32_t>(load_le32(c.take(4, what))); }
float le_f32(Cursor& c, const char* what) { return bits_to_float(load_le32(c.take(4, what))); }

UniHeader read_uni_header(Cursor& c, const char* magic, const char* kind) {
    const unsigned char* m = c.take(4, "the magic");
    if (std::memcmp(m, magic, 4) != 0)
        c.fail(std::string("not a Mantaflow ") + kind + " file: it starts with " +
               quote(std::string_view(reinterpret_cast<const char*>(m), 4)) + ", not '" + magic + "'");
    UniHeader h;
    const std::size_t count_at = c.pos();
    h.count = le_i32(c, "the particle count");
    for (int k = 0; k < 3; ++k) h.grid[k] = le_i32(c, "the grid size");
    h.element_type = le_i32(c, "the element type");
    h.element_bytes = le_i32(c, "the element size");
    c.take(256 + 8, "the header's info string and timestamp");
    if (h.count < 0) c.fail("negative particle count " + std::to_string(h.count) + " at " + c.where(count_at));
    for (int k = 0; k < 3; ++k)
        if (h.grid[k] <= 0 || h.grid[k] > kMaxGridCells)
            c.fail("grid size " + std::to_string(h.grid[0]) + " x " + std::to_string(h.grid[1]) + " x " +
                   std::to_string(h.grid[2]) + " at " + c.where(count_at + 4) + " is not a grid Mantaflow writes");
    return h;
}

// The data after the header must be exactly count elements.
void require_exact_payload(Cursor& c, const UniHeader& h, const char* what) {
    std::uint64_t bytes = 0;
    checked_mul(static_cast<std::uint64_t>(h.count), static_cast<std::uint64_t>(h.element_bytes), bytes);
    c.require(bytes, std::to_string(h.count) + " " + what);
    if (c.remaining() != bytes)
        c.fail(std::to_string(c.remaining() - bytes) + " bytes after the last of " + std::to_string(h.count) + " " +
               what + " (from " + c.where(c.pos() + bytes) + "): the count in the header is wrong");
}

std::string grid_text(const std::array<int, 3>& g) {
    return std::to_string(g[0]) + " x " + std::to_string(g[1]) + " x " + std::to_string(g[2]);
}

// "<dir>/pp_0012.uni" -> {"pp_", "0012"}: the name before the frame number and the number's digits.
bool split_frame_name(const std::filesystem::path& file, std::string& prefix, std::string& digits) {
    std::string stem = path_to_utf8(file.filename());
    for (const char* ext : {".gz", ".bobj", ".uni", ".vdb"}) {
        const std::string e = ext;
        if (stem.size() > e.size() && to_lower(stem.substr(stem.size() - e.size())) == e) stem.resize(stem.size() - e.size());
    }
    std::size_t end = stem.size(), begin = end;
    while (begin > 0 && std::isdigit(static_cast<unsigned char>(stem[begin - 1]))) --begin;
    if (begin == end) return false;
    prefix = stem.substr(0, begin);
    digits = stem.substr(begin);
    return true;
}

bool is_file(const std::filesystem::path& p) {
    std::error_code ec;
    return std::filesystem::is_regular_file(p, ec);
}

// Reads and gunzips a sibling file of the cache and hands its bytes to `parse`; its errors name the file that was
// asked for first (`path`), then the sibling.
template <class Parse>
auto read_sibling(const std::string& path, const std::filesystem::path& file, const char* what, Parse parse) {
    const std::string sibling = path_to_utf8(file);
    try {
        Bytes bytes = read_file(sibling);
        const bool compressed = has_gzip_magic(bytes);
        if (compressed) bytes = gunzip(sibling, bytes);
        return parse(Source{sibling, bytes.data(), bytes.size(), compressed});
    } catch (const FormatError& e) {
        fail(path, std::string("its ") + what + " cannot be read: " + e.what());
    }
}

// The config of the frame that `file` (<cache>/data/pp_0012.uni or <cache>/mesh/fluid_mesh_0012.bobj.gz) belongs to.
FluidDomain domain_for(const std::string& path, const char* what, MantaflowConfig* config_out = nullptr) {
    const std::filesystem::path file = path_from_utf8(path);
    std::string prefix, digits;
    if (!split_frame_name(file, prefix, digits))
        fail(path, std::string(what) + " are in Mantaflow's grid space, placed in the world by the cache's "
                   "config/config_####.uni of the same frame, but the file name has no frame number to find it by "
                   "(keep Blender's names, e.g. pp_0012.uni)");
    const std::filesystem::path config = file.parent_path().parent_path() / "config" / path_from_utf8("config_" + digits + ".uni");
    if (!is_file(config))
        fail(path, std::string(what) + " are in Mantaflow's grid space, placed in the world by the cache's " +
                   path_to_utf8(config) + ", which does not exist (Blender writes it with every baked frame; keep "
                   "the cache folder's layout: data/ and mesh/ next to config/)");
    return read_sibling(path, config, "cache config", [&](const Source& s) {
        const MantaflowConfig parsed = parse_mantaflow_config(s);
        if (config_out) *config_out = parsed;
        return fluid_domain_from_config(parsed, s.path);
    });
}

std::array<double, 3> world_of_grid(const FluidDomain& d, double i, double j, double k) {
    std::array<double, 3> w;
    for (int c = 0; c < 3; ++c) w[c] = d.origin[c] + i * d.axes[0][c] + j * d.axes[1][c] + k * d.axes[2][c];
    return w;
}

// Grid cells per Mantaflow time unit -> m/s in the world, along the domain's axes.
std::array<float, 3> world_velocity(const FluidDomain& d, const float* v) {
    std::array<float, 3> w;
    for (int k = 0; k < 3; ++k)
        w[k] = static_cast<float>(kMantaflowTimeUnitsPerSecond * (v[0] * d.axes[0][k] + v[1] * d.axes[1][k] + v[2] * d.axes[2][k]));
    return w;
}

}  // namespace

MantaflowParticleSystem parse_mantaflow_particle_system(const Source& source) {
    Cursor c(source);
    if (c.size() >= 4 && std::memcmp(c.here(), "PB01", 4) == 0)
        c.fail("Mantaflow particle file version PB01 (before 2017) is not supported; re-bake with a current Blender");
    const UniHeader h = read_uni_header(c, "PB02", "particle system");
    if (h.element_bytes != 16)
        c.fail("particle element size " + std::to_string(h.element_bytes) + " at " + c.where(24) +
               " is not Mantaflow's basic particle (16 bytes: position and flag)");
    require_exact_payload(c, h, "particles");
    MantaflowParticleSystem out;
    out.grid = h.grid;
    out.positions.resize(3 * static_cast<std::size_t>(h.count));
    out.flags.resize(static_cast<std::size_t>(h.count));
    for (std::size_t i = 0; i < out.flags.size(); ++i) {
        const std::size_t at = c.pos();
        const unsigned char* p = c.take(16, "a particle");
        for (int k = 0; k < 3; ++k) {
            const float v = bits_to_float(load_le32(p + 4 * k));
            if (!std::isfinite(v)) c.fail("particle " + std::to_string(i) + " has a non-finite position at " + c.where(at));
            out.positions[3 * i + k] = v;
        }
        out.flags[i] = static_cast<std::int32_t>(load_le32(p + 12));
    }
    return out;
}

std::vector<float> parse_mantaflow_vec3_data(const Source& source, std::size_t count, const std::array<int, 3>& grid) {
    Cursor c(source);
    const UniHeader h = read_uni_header(c, "PD01", "particle data");
    if (h.element_bytes != 12)
        c.fail("particle data of element size " + std::to_string(h.element_bytes) + " (type " +
               std::to_string(h.element_type) + ") at " + c.where(24) + " is not a 3-vector of floats (12 bytes)");
    if (static_cast<std::size_t>(h.count) != count || h.grid != grid)
        c.fail("holds " + std::to_string(h.count) + " values on a " + grid_text(h.grid) + " grid, but its particle file has " +
               std::to_string(count) + " particles on a " + grid_text(grid) + " grid (files from different bakes?)");
    require_exact_payload(c, h, "vectors");
    std::vector<float> out(3 * count);
    decode_to_float(c.take(12 * static_cast<std::uint64_t>(count), "the vectors"), 3 * count, ScalarType::f32, false, out.data());
    return out;
}

MantaflowConfig parse_mantaflow_config(const Source& source) {
    Cursor c(source);
    if (c.size() < kConfigBytes)
        c.fail("a Mantaflow cache config holds " + std::to_string(kConfigBytes) + " bytes, this one " +
               std::to_string(c.size()) + " (truncated, or not a config_####.uni)");
    MantaflowConfig m;
    le_i32(c, "the active fields");
    for (int k = 0; k < 3; ++k) m.resolution[k] = le_i32(c, "the resolution");
    m.dx = le_f32(c, "dx");
    m.frame_length = le_f32(c, "dt");
    for (int k = 0; k < 3; ++k) m.p0[k] = le_f32(c, "p0");
    for (int k = 0; k < 3; ++k) m.p1[k] = le_f32(c, "p1");
    c.take(12 + 12 + 12, "dp0, shift and the object shift");
    for (int k = 0; k < 16; ++k) m.object_to_world[k] = le_f32(c, "the object matrix");
    for (int k = 0; k < 3; ++k) m.base_resolution[k] = le_i32(c, "the base resolution");
    for (int k = 0; k < 3; ++k) m.res_min[k] = le_i32(c, "the minimum resolution");
    for (int k = 0; k < 3; ++k) m.res_max[k] = le_i32(c, "the maximum resolution");
    for (int k = 0; k < 3; ++k) {
        if (m.resolution[k] <= 0 || m.resolution[k] > kMaxGridCells || m.base_resolution[k] <= 0 ||
            m.base_resolution[k] > kMaxGridCells || m.res_min[k] < -kMaxGridCells || m.res_max[k] > kMaxGridCells ||
            m.res_max[k] <= m.res_min[k])
            c.fail("resolution " + grid_text(m.resolution) + " (base " + grid_text(m.base_resolution) + ", from " +
                   grid_text(m.res_min) + " to " + grid_text(m.res_max) + ") at " + c.where(4) + " is not a domain's grid");
        if (!(m.p1[k] > m.p0[k]) || !std::isfinite(m.p0[k]) || !std::isfinite(m.p1[k]))
            c.fail("the domain's bounds p0 / p1 at " + c.where(24) + " are empty or not finite");
    }
    if (!(m.dx > 0.0f) || !std::isfinite(m.dx)) c.fail("dx " + std::to_string(m.dx) + " at " + c.where(16) + " is not positive");
    for (float v : m.object_to_world)
        if (!std::isfinite(v)) c.fail("the domain object's matrix at " + c.where(84) + " is not finite");
    return m;
}

constexpr double kBlenderDefaultBandWidthCells = 3.0;

FluidDomain fluid_domain_from_config(const MantaflowConfig& m, const std::string& config_path) {
    const auto& M = m.object_to_world;
    std::array<std::array<double, 3>, 3> unit_axis{};
    std::array<double, 3> scale{};
    for (int i = 0; i < 3; ++i) {
        double n2 = 0.0;
        for (int r = 0; r < 3; ++r) n2 += double(M[4 * i + r]) * M[4 * i + r];
        scale[i] = std::sqrt(n2);
        if (!(scale[i] > 1e-30)) fail(config_path, "the domain object's matrix has a zero scale on axis " + std::to_string(i));
        for (int r = 0; r < 3; ++r) unit_axis[i][r] = M[4 * i + r] / scale[i];
    }
    // Blender's max_size: the longest world extent of the grid; one cell is that over the resolution setting.
    double longest = 0.0;
    for (int i = 0; i < 3; ++i) {
        const double cell = (double(m.p1[i]) - m.p0[i]) / m.base_resolution[i];
        longest = std::max(longest, cell * scale[i] * (m.res_max[i] - m.res_min[i]));
    }
    const double h = longest * m.dx;
    FluidDomain d;
    d.resolution = m.resolution;
    // The cache does not record how deep the band of FLIP particles reaches: Blender's default Narrow Band Width (3
    // cells) lets the narrow-band fill run on a cache read alone. A wider band (a whole liquid of particles) leaves no
    // hollow for the fill to find, so assuming the default there adds nothing; the add-on passes the domain's value.
    d.band_width_cells = kBlenderDefaultBandWidthCells;
    for (int k = 0; k < 16; ++k) d.object_to_world[k] = M[k];
    for (int r = 0; r < 3; ++r) d.origin[r] = M[12 + r];
    for (int i = 0; i < 3; ++i) {
        const double centre = 0.5 * (double(m.p0[i]) + m.p1[i]);
        for (int r = 0; r < 3; ++r) {
            d.axes[i][r] = unit_axis[i][r] * h;
            d.origin[r] += unit_axis[i][r] * (scale[i] * centre - 0.5 * m.resolution[i] * h);
        }
    }
    return d;
}

TriMesh parse_mantaflow_bobj(const Source& source) {
    Cursor c(source);
    TriMesh mesh;
    auto count = [&](const char* what, std::uint64_t element_bytes) {
        const std::size_t at = c.pos();
        const std::int32_t n = le_i32(c, what);
        if (n < 0) c.fail(std::string("negative ") + what + " " + std::to_string(n) + " at " + c.where(at));
        c.require(static_cast<std::uint64_t>(n) * element_bytes, std::to_string(n) + " " + what);
        return static_cast<std::size_t>(n);
    };
    const std::size_t vertices = count("vertex count", 12);
    mesh.vertices.resize(3 * vertices);
    decode_to_float(c.take(12 * vertices, "the vertices"), 3 * vertices, ScalarType::f32, false, mesh.vertices.data());
    const std::size_t bad = first_non_finite(mesh.vertices);
    if (bad < mesh.vertices.size()) c.fail("vertex " + std::to_string(bad / 3) + " is not finite at " + c.where(4 + 4 * bad));
    const std::size_t normals = count("normal count", 12);
    if (normals != 0 && normals != vertices)
        c.fail(std::to_string(normals) + " normals for " + std::to_string(vertices) + " vertices");
    c.take(12 * normals, "the normals");  // recomputed from the placed mesh by whoever needs them
    const std::size_t triangles = count("triangle count", 12);
    const std::size_t triangles_at = c.pos();
    mesh.triangles.resize(3 * triangles);
    const unsigned char* t = c.take(12 * triangles, "the triangles");
    for (std::size_t i = 0; i < 3 * triangles; ++i) {
        const std::int32_t v = static_cast<std::int32_t>(load_le32(t + 4 * i));
        if (v < 0 || static_cast<std::size_t>(v) >= vertices)
            c.fail("triangle " + std::to_string(i / 3) + " uses vertex " + std::to_string(v) + " of " + std::to_string(vertices) +
                   " at " + c.where(triangles_at + 4 * i));
        mesh.triangles[i] = v;
    }
    if (!c.at_end())
        c.fail(std::to_string(c.remaining()) + " bytes after the last triangle (from " + c.where() +
               "): a mesh with a velocity or other extra block is not a bobj Mantaflow writes");
    return mesh;
}

ParticleData read_mantaflow_uni_particles(const Source& source) {
    MantaflowParticleSystem system = parse_mantaflow_particle_system(source);
    const FluidDomain domain = domain_for(source.path, "Mantaflow particle positions");
    if (system.grid != domain.resolution)
        fail(source.path, "the particles are on a " + grid_text(system.grid) + " grid but the cache's config of that frame says " +
                          grid_text(domain.resolution) + " (files from different bakes?)");

    // The velocities of the same particles, when the cache has them: <dir>/pVel_0012.uni next to pp_0012.uni.
    const std::filesystem::path file = path_from_utf8(source.path);
    std::string prefix, digits;
    std::vector<float> velocity;
    if (split_frame_name(file, prefix, digits) && prefix.size() >= 2 && prefix.compare(0, 2, "pp") == 0) {
        const std::filesystem::path vel = file.parent_path() / path_from_utf8("pVel" + prefix.substr(2) + digits + ".uni");
        if (is_file(vel))
            velocity = read_sibling(source.path, vel, "velocities", [&](const Source& s) { return parse_mantaflow_vec3_data(s, system.flags.size(), system.grid); });
    }

    ParticleData out;
    out.positions.reserve(system.positions.size());
    if (!velocity.empty()) out.attributes.push_back(Attribute{"velocity", 3, {}, false});
    for (std::size_t i = 0; i < system.flags.size(); ++i) {
        if (system.flags[i] & (kParticleDeleted | kParticleInvalid)) continue;
        const float* g = &system.positions[3 * i];
        const auto w = world_of_grid(domain, g[0], g[1], g[2]);
        for (int k = 0; k < 3; ++k) out.positions.push_back(static_cast<float>(w[k]));
        if (!velocity.empty())
            for (float v : world_velocity(domain, &velocity[3 * i])) out.attributes[0].values.push_back(v);
    }
    out.fluid_domain = domain;
    return out;
}

ParticleData read_vdb_particles(const Source& source) {
    ParticleData p = read_vdb_points(source);
    std::string prefix, digits;
    if (!split_frame_name(path_from_utf8(source.path), prefix, digits) || prefix != "fluid_data_") return p;
    // Blender's OpenVDB data cache: the points are in grid cells times the cell size; the config places them.
    const FluidDomain domain = domain_for(source.path, "Mantaflow's OpenVDB particle positions");
    const auto& a = domain.axes;
    const double cell = std::sqrt(a[0][0] * a[0][0] + a[0][1] * a[0][1] + a[0][2] * a[0][2]);
    for (std::size_t i = 0; i < p.size(); ++i) {
        float* x = &p.positions[3 * i];
        const auto w = world_of_grid(domain, x[0] / cell, x[1] / cell, x[2] / cell);
        for (int k = 0; k < 3; ++k) x[k] = static_cast<float>(w[k]);
    }
    for (Attribute& attribute : p.attributes)
        if (attribute.name == "particles_velocity" && attribute.components == 3) {
            attribute.name = "velocity";
            for (std::size_t i = 0; i < p.size(); ++i) {
                const auto w = world_velocity(domain, &attribute.values[3 * i]);
                std::copy(w.begin(), w.end(), attribute.values.begin() + 3 * i);
            }
        }
    p.fluid_domain = domain;
    return p;
}

TriMesh read_mantaflow_bobj_mesh(const Source& source) {
    TriMesh mesh = parse_mantaflow_bobj(source);
    MantaflowConfig config;
    const FluidDomain domain = domain_for(source.path, "Mantaflow mesh vertices", &config);
    // bobj vertices are (grid - resolution/2) / the longest resolution; back to grid index space, then placed.
    const double longest = std::max({config.resolution[0], config.resolution[1], config.resolution[2]});
    for (std::size_t v = 0; v < mesh.num_vertices(); ++v) {
        float* p = &mesh.vertices[3 * v];
        const auto w = world_of_grid(domain, p[0] * longest + 0.5 * config.resolution[0], p[1] * longest + 0.5 * config.resolution[1],
                                     p[2] * longest + 0.5 * config.resolution[2]);
        for (int k = 0; k < 3; ++k) p[k] = static_cast<float>(w[k]);
    }
    // A mirrored domain object turns the triangles inside out; keep them counter-clockwise seen from outside.
    const auto& a = domain.axes;
    const double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                       a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    if (det < 0.0)
        for (std::size_t t = 0; t < mesh.num_triangles(); ++t) std::swap(mesh.triangles[3 * t + 1], mesh.triangles[3 * t + 2]);
    return mesh;
}

}  // namespace io_detail
}  // namespace meniscus
