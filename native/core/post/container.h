// The container's mesh box after reconstruction (splashsurf's --mesh-aabb-min/max, --mesh-aabb-clamp-verts).
// Capped (the default), marching cubes already closed the surface with flat faces on the walls (surface/bricks.h,
// MeshBox); here its wall vertices are found, for the stages that must keep them on their walls
// (post/wall_constraints.h). Open, the surface is cut at the box like splashsurf does.
#pragma once
#include <cstddef>

#include "mesh/adjacency.h"
#include "mesh/mesh.h"
#include "parameters.h"
#include "post/wall_constraints.h"
#include "sph/neighborhood.h"

namespace meniscus {

// The vertices lying exactly on a wall plane (marching cubes writes the plane's coordinate itself, and the stages
// before smoothing never move such a vertex; see the pipeline), with the planes.
WallConstraints find_wall_vertices(const TriMesh& mesh, const Vector3& lower, const Vector3& upper, int threads);

// Marching cubes cuts the box's edges (where two walls meet) across one cube: a bevel joins a vertex on one wall to
// vertices on the other. Moves such a vertex onto the edge itself (of walls a and b, the vertex on the wall listed
// first in WallConstraints' order moves), so both caps reach the edge and the bevel's faces lie on the other wall.
// A move that would leave a triangle without area is not made. Updates the mask; returns the vertices moved.
std::size_t square_box_edges(TriMesh& mesh, WallConstraints& walls);

// The particles' hat-weighted neighbour counts (sorted order, Eq. 10-11) as if the fluid were mirrored at the walls:
// for a particle within the kernel support of a wall, the neighbours beyond the wall are replaced by the mirror
// images of those inside. Particles that end at a tank wall then count as bulk there, so the feature weights do not
// take the free surface next to the wall for a thin feature (the wall side is not a free surface). Diagonal images
// at the box's edges and corners are left out.
std::vector<float> counts_mirrored_at_walls(const ParticleGrid& grid, const std::vector<float>& counts, const Vector3& lower,
                                            const Vector3& upper, double support, int threads);

// How much smoothing moves each vertex (`amount`, empty: 1 everywhere), on the walls: 1, since a wall is flat, not
// a free surface (its particles' counts, cut off by the wall, would call it one).
std::vector<float> smoothing_amount_at_walls(const WallConstraints& walls, std::vector<float> amount);

// The neighbours smoothing averages over, with walls. The contact line (wall vertices with a neighbour off the
// walls) is smoothed along itself only: over its neighbours on the contact line, none when it has fewer than two.
// Marching cubes leaves it as a staircase of lattice points on the wall, which this straightens; the cap, pulling it
// along the wall, would drag the free surface down into a fillet. Other vertices keep all their neighbours.
CsrList smoothing_neighbours_at_walls(const WallConstraints& walls, const CsrList& neighbours);

// Open cut: removes the triangles with all three vertices outside the box and the vertices no triangle uses
// (normals and attributes follow); with clamp_vertices, then moves the vertices outside onto the box's faces.
// Returns the number of triangles removed.
std::size_t cut_open_at_box(TriMesh& mesh, const Vector3& lower, const Vector3& upper, bool clamp_vertices);

// Clamps every vertex coordinate into the box. Returns the number of vertices moved.
std::size_t clamp_into_box(TriMesh& mesh, const Vector3& lower, const Vector3& upper);

}  // namespace meniscus
