// Solid water from narrow-band particles. Mantaflow keeps FLIP particles only a few cells deep under the liquid's
// surface (FluidDomain::band_width_cells), so they form a shell and a surface made from them alone is hollow. This
// classifies the solver's grid cells as shell (near a particle), solid (closed borders, obstacles), liquid (what the
// shell encloses) or air, and puts extra particles on a lattice in the liquid cells, each taking the attributes of a
// nearby particle: the unchanged pipeline then makes a solid surface that follows the particles where they are.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sph/fluid_domain.h"
#include "sph/particles.h"

namespace meniscus {

enum class CellClass : uint8_t { air = 0, shell = 1, liquid = 2, solid = 3 };

struct InteriorClassification {
    std::array<int, 3> resolution{0, 0, 0};
    std::vector<CellClass> cells;  // index i + nx * (j + ny * k)
    int components = 0;            // connected regions of cells that are neither shell nor solid
    int enclosed_components = 0;   // of them, those surrounded by shell on all sides (a droplet's hollow, a bubble)
    int split_components = 0;      // of them, those classified cell by cell (an air region and the liquid joined
                                   // through an obstacle the fill was not told about, or a hole in the shell)

    std::size_t count(CellClass c) const;
};

// InputError naming the field (fluid_domain.resolution, ...) when the domain cannot describe a grid.
void validate_fluid_domain(const FluidDomain& domain);

// The cells' classes. Deterministic: the same cells for any thread count.
InteriorClassification classify_interior(const PositionsView& positions, const FluidDomain& domain, int threads);

struct InteriorFill {
    std::vector<float> positions;   // 3 * count, world space, in cell order
    std::vector<uint32_t> source;   // per fill particle: the original particle whose attributes it takes
    InteriorClassification classification;
};

// Whether the fill applies by itself (fill_interior automatic): the particles come from a narrow band.
bool narrow_band_domain(const FluidDomain& domain);

// Fill particles on a lattice of about `spacing` (world units; the particles' rest spacing, 2 r) in the cells the
// shell encloses. ResourceError beyond the memory budget (0: the default budget).
InteriorFill fill_interior(const PositionsView& positions, const FluidDomain& domain, double spacing, int threads,
                           std::size_t memory_budget_bytes);

}  // namespace meniscus
