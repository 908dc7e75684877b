// NumPy particle readers: .npy (format versions 1.0, 2.0 and 3.0) and .npz (a zip archive of .npy members, as
// written by numpy.savez and numpy.savez_compressed).
//
// .npy: an (N, 3) array of positions in any integer or float type (float16 to float64, either byte order, C or
// Fortran order), or a structured array of shape (N,) whose fields x, y, z (or one 3-component field named
// position / positions / pos / points / xyz) are the positions and whose other numeric fields are attributes.
//
// .npz: the positions are the member named positions / position / pos / points / particles / xyz, else the first
// (N, 3) member; separate 1-D members x, y and z work too, and so does a structured member. Every other numeric member
// whose first dimension is N becomes an attribute named after it, with the product of the other dimensions as its
// component count; members of another length (a frame time, a box) are not particle data and are left out. Zip
// members may be stored or deflated, with or without zip64 records (numpy always writes zip64 extra fields);
// other compression methods and encryption are refused by name.
//
// Object arrays (pickles) are never loaded: they could run code. The .npy parsing itself is npy.cpp; the zip
// archive is parsers/zip.cpp.
#include <algorithm>

#include "io/formats/npy.h"
#include "io/parsers/zip.h"

namespace meniscus {
namespace io_detail {
namespace {


bool is_position_name(const std::string& name) {
    static const char* names[] = {"positions", "position", "pos", "points", "particles", "xyz", "p", "P"};
    for (const char* n : names)
        if (name == n) return true;
    return false;
}

// Positions from a structured array's columns (x, y, z or one 3-component position field); the rest become
// attributes. False when the array has no positions.
bool take_structured(NpyArray& array, ParticleData& out) {
    auto find = [&](auto pred) -> int {
        for (std::size_t i = 0; i < array.columns.size(); ++i)
            if (pred(array.columns[i])) return static_cast<int>(i);
        return -1;
    };
    const std::size_t n = static_cast<std::size_t>(array.rows());
    int ix = find([](const NpyColumn& c) { return c.components == 1 && (c.name == "x" || c.name == "X"); });
    int iy = find([](const NpyColumn& c) { return c.components == 1 && (c.name == "y" || c.name == "Y"); });
    int iz = find([](const NpyColumn& c) { return c.components == 1 && (c.name == "z" || c.name == "Z"); });
    std::vector<bool> used(array.columns.size(), false);
    if (ix >= 0 && iy >= 0 && iz >= 0) {
        out.positions.resize(3 * n);
        int idx[3] = {ix, iy, iz};
        for (int k = 0; k < 3; ++k) {
            const auto& v = array.columns[static_cast<std::size_t>(idx[k])].values;
            for (std::size_t i = 0; i < n; ++i) out.positions[3 * i + k] = v[i];
            used[static_cast<std::size_t>(idx[k])] = true;
        }
    } else {
        int ip = find([](const NpyColumn& c) { return c.components == 3 && is_position_name(c.name); });
        if (ip < 0) return false;
        out.positions = std::move(array.columns[static_cast<std::size_t>(ip)].values);
        used[static_cast<std::size_t>(ip)] = true;
    }
    for (std::size_t i = 0; i < array.columns.size(); ++i) {
        if (used[i]) continue;
        Attribute a;
        a.name = array.columns[i].name;
        a.components = array.columns[i].components;
        a.values = std::move(array.columns[i].values);
        a.integral = array.columns[i].integral;
        out.attributes.push_back(std::move(a));
    }
    return true;
}

bool is_positions_shape(const NpyArray& a) { return !a.structured && a.shape.size() == 2 && a.shape[1] == 3; }

// The .npz reader: every .npy member parsed, then the positions chosen and the other per-particle members added.
class NpzReader {
public:
    explicit NpzReader(const Source& source) : source_(source) {}

    ParticleData read() {
        read_members();
        if (arrays_.empty()) fail(source_.path, "the .npz archive has no .npy members");
        used_.assign(arrays_.size(), false);
        ParticleData out;
        if (!take_positions_member(out) && !take_xyz_members(out) && !take_structured_member(out))
            fail(source_.path, "no particle positions in the .npz archive: expected an (N, 3) member (preferably named "
                               "'positions'), members x, y and z, or a structured member with fields x, y, z; it has: " + listing_);
        add_attributes(out);
        return out;
    }

private:
    struct Member {
        std::string name;  // without ".npy"
        NpyArray array;
    };
    const Source& source_;
    std::vector<Member> arrays_;
    std::vector<bool> used_;  // members that gave the positions
    std::string listing_;     // "name shape, ..." for messages

    void read_members() {
        ZipReader zip(source_);
        std::uint64_t budget = max_inflated_size(source_.size);
        for (const auto& m : zip.members()) {
            if (m.name.size() < 4 || m.name.compare(m.name.size() - 4, 4, ".npy") != 0) continue;  // not an array
            Bytes bytes = zip.extract(m, budget);
            Source member{source_.path + ": member " + quote(m.name), bytes.data(), bytes.size(), m.method != 0};
            Member named{m.name.substr(0, m.name.size() - 4), parse_npy(member)};
            listing_ += (listing_.empty() ? "" : ", ") + named.name + " " + (named.array.structured ? "structured " : "") +
                        shape_text(named.array.shape);
            arrays_.push_back(std::move(named));
        }
    }

    // An (N, 3) member: the one with a position name, else the first.
    bool take_positions_member(ParticleData& out) {
        int chosen = -1;
        for (std::size_t i = 0; i < arrays_.size() && chosen < 0; ++i)
            if (is_position_name(arrays_[i].name) && is_positions_shape(arrays_[i].array)) chosen = static_cast<int>(i);
        for (std::size_t i = 0; i < arrays_.size() && chosen < 0; ++i)
            if (is_positions_shape(arrays_[i].array)) chosen = static_cast<int>(i);
        if (chosen < 0) return false;
        out.positions = std::move(arrays_[static_cast<std::size_t>(chosen)].array.columns[0].values);
        used_[static_cast<std::size_t>(chosen)] = true;
        return true;
    }

    // Separate 1-D members x, y and z of one length.
    bool take_xyz_members(ParticleData& out) {
        int idx[3] = {-1, -1, -1};
        for (std::size_t i = 0; i < arrays_.size(); ++i)
            for (int k = 0; k < 3; ++k)
                if (arrays_[i].name == std::string(1, "xyz"[k]) && !arrays_[i].array.structured && arrays_[i].array.shape.size() == 1)
                    idx[k] = static_cast<int>(i);
        if (idx[0] < 0 || idx[1] < 0 || idx[2] < 0) return false;
        const std::uint64_t n = arrays_[static_cast<std::size_t>(idx[0])].array.shape[0];
        for (int k = 1; k < 3; ++k)
            if (arrays_[static_cast<std::size_t>(idx[k])].array.shape[0] != n)
                fail(source_.path, "the members x, y and z have different lengths (" + listing_ + ")");
        out.positions.resize(static_cast<std::size_t>(3 * n));
        for (int k = 0; k < 3; ++k) {
            const auto& v = arrays_[static_cast<std::size_t>(idx[k])].array.columns[0].values;
            for (std::size_t i = 0; i < n; ++i) out.positions[3 * i + k] = v[i];
            used_[static_cast<std::size_t>(idx[k])] = true;
        }
        return true;
    }

    // The first structured member with positions inside; its other fields become attributes.
    bool take_structured_member(ParticleData& out) {
        for (std::size_t i = 0; i < arrays_.size(); ++i)
            if (arrays_[i].array.structured && take_structured(arrays_[i].array, out)) {
                used_[i] = true;
                return true;
            }
        return false;
    }

    // Every other member whose first dimension is the particle count (others, a frame time or a box, are not
    // per-particle data), named after the member (and the field, for structured members).
    void add_attributes(ParticleData& out) {
        const std::size_t n = out.size();
        for (std::size_t i = 0; i < arrays_.size(); ++i) {
            if (used_[i]) continue;
            NpyArray& a = arrays_[i].array;
            if (a.shape.empty() || a.shape[0] != n) continue;
            for (auto& col : a.columns) {
                if (a.rows() != 0 && col.values.size() / a.rows() > 65536) continue;
                Attribute attr;
                attr.name = a.structured ? arrays_[i].name + "." + col.name : arrays_[i].name;
                attr.components = n ? static_cast<int>(col.values.size() / n) : std::max(col.components, 1);
                if (attr.components == 0) continue;
                attr.values = std::move(col.values);
                attr.integral = col.integral;
                out.attributes.push_back(std::move(attr));
            }
        }
    }
};

}  // namespace

ParticleData read_npy_particles(const Source& source) {
    NpyArray array = parse_npy(source);
    ParticleData out;
    if (array.structured) {
        if (!take_structured(array, out))
            fail(source.path, "the structured array has no fields x, y, z and no 3-component field named position, "
                              "positions, pos, points, particles or xyz");
        return out;
    }
    if (!is_positions_shape(array))
        fail(source.path, "the array has shape " + shape_text(array.shape) + "; particle positions need shape (N, 3)");
    out.positions = std::move(array.columns[0].values);
    return out;
}

ParticleData read_npz_particles(const Source& source) { return NpzReader(source).read(); }

}  // namespace io_detail
}  // namespace meniscus
