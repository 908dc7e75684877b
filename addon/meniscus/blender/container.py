"""The container of a surface: a chosen object whose world-space bounds, as they are at the frame being built
(following its animation), give the mesh box (and, when asked for, the particle box) of the reconstruction.

The bounds are computed from plain sequences, so this module needs no bpy and is tested without Blender too.
"""


def world_bounds(corners, matrix):
    """Lower and upper corners, as tuples, of the axis-aligned box around `corners` (an object's 8 local bounding-box
    corners) mapped by `matrix` (its 4x4 world matrix, rows indexable): a rotated object gets the box around it."""
    points = []
    for corner in corners:
        x, y, z = (float(c) for c in corner)
        points.append(tuple(matrix[row][0] * x + matrix[row][1] * y + matrix[row][2] * z + matrix[row][3] for row in range(3)))
    lower = tuple(min(p[k] for p in points) for k in range(3))
    upper = tuple(max(p[k] for p in points) for k in range(3))
    return lower, upper


def box_arguments(settings):
    """api.reconstruct's box keywords from a surface's settings: the container object's bounds as the mesh box (and
    the particle box when the user asked for it); every box unset without a container or with a flat one (a plane
    has no inside, and the core would refuse the box naming parameters the user never sees)."""
    arguments = {"mesh_aabb_min": None, "mesh_aabb_max": None, "particle_aabb_min": None, "particle_aabb_max": None}
    obj = settings.container_object
    if obj is None:
        return arguments
    # The original object's matrix_world and bound_box are those of the frame the depsgraph last evaluated: the
    # frame being built, since the frame-change handler runs after the scene has moved to it.
    lower, upper = world_bounds(obj.bound_box, obj.matrix_world)
    if not all(lo < hi for lo, hi in zip(lower, upper)):
        return arguments
    arguments["mesh_aabb_min"], arguments["mesh_aabb_max"] = lower, upper
    if settings.use_container_particle_box:
        arguments["particle_aabb_min"], arguments["particle_aabb_max"] = lower, upper
    return arguments
