"""A Mantaflow liquid domain (Blender's fluid simulation) as a source: the frame's FLIP particles come from the
domain's cache files through the core's reader, never from what the domain shows. The evaluated domain is the wrong
thing to read: hidden from renders or outside the bake it is its box (8 corners), with FLIP display off it is
Mantaflow's own surface, and its particle system follows the display amount.

Also here: the fluid domain the core's narrow-band fill needs (walls, gravity, band depth, obstacles; the grid's
placement comes from the cache's config through the reader), and the defaults derived from the domain's grid.
"""
import os

import bpy
import numpy as np

# Mantaflow's particle files in <cache>/data/, by the domain's data format (Blender's fluid cache layout).
_PARTICLE_FILES = {"UNI": "pp_{:04d}.uni", "OPENVDB": "fluid_data_{:04d}.vdb"}
# Closed borders in FluidDomain's order (-x, +x, -y, +y, -z, +z): Blender's left/right are x, front/back y.
_BORDERS = ("left", "right", "front", "back", "bottom", "top")
# What Meniscus' iso threshold must be to put the surface where Mantaflow's mesh puts it around particles of
# radius one half cell (measured on the baked test scenes: tests/python/test_interior_fill.py).
MANTAFLOW_ISO_THRESHOLD = 0.45


class DomainError(ValueError):
    """A liquid domain that cannot give particles at this frame, in the artist's terms (no traceback)."""


def domain_settings(obj):
    """The FluidDomainSettings of a Mantaflow domain object, else None."""
    if obj is None or obj.type != "MESH":
        return None
    for modifier in obj.modifiers:
        if modifier.type == "FLUID" and modifier.fluid_type == "DOMAIN":
            return modifier.domain_settings
    return None


def is_liquid_domain(obj):
    settings = domain_settings(obj)
    return settings is not None and settings.domain_type == "LIQUID"


def cache_folder(obj):
    """The domain's cache folder as Blender resolves it: '//' from the .blend (a linked domain: from its library)."""
    settings = domain_settings(obj)
    return os.path.normpath(bpy.path.abspath(settings.cache_directory, library=obj.library))


def cache_frame(obj, scene_frame):
    """The cache frame Blender loads at a scene frame: a baked cache (types All and Modular) plays Frame Offset
    frames later; a Replay cache follows the scene's frames."""
    settings = domain_settings(obj)
    offset = 0 if settings.cache_type == "REPLAY" else settings.cache_frame_offset
    return int(round(scene_frame)) - offset


def particle_file(obj, scene_frame):
    """The particle file of the frame; raises DomainError naming the domain, the frames and the path when it cannot
    be read."""
    settings = domain_settings(obj)
    if settings is None:
        raise DomainError(f"'{obj.name}' is not a fluid domain")
    if settings.domain_type != "LIQUID":
        raise DomainError(f"'{obj.name}' is a {settings.domain_type.lower()} domain: only a liquid domain has "
                          "particles to surface")
    frame = cache_frame(obj, scene_frame)
    offset = f" (frame {int(round(scene_frame))} - Frame Offset {settings.cache_frame_offset})" \
        if frame != int(round(scene_frame)) else ""
    data_format = settings.cache_data_format
    if data_format not in _PARTICLE_FILES:
        raise DomainError(f"'{obj.name}': cache data format {data_format} has no particle files Meniscus reads "
                          "(use Uni Cache or OpenVDB)")
    path = os.path.join(cache_folder(obj), "data", _PARTICLE_FILES[data_format].format(frame))
    if not os.path.isfile(path):
        if not settings.cache_frame_start <= frame <= settings.cache_frame_end:
            where = f"outside the domain's cache frames {settings.cache_frame_start}-{settings.cache_frame_end}"
        else:
            where = "not baked"
        raise DomainError(f"Missing fluid particles of '{obj.name}' for cache frame {frame}{offset}, {where}: {path}")
    return path


def baked_scene_frames(obj):
    """The scene frames whose particle file is on disk (what HOLD can fall back on), from one folder listing."""
    settings = domain_settings(obj)
    pattern = _PARTICLE_FILES.get(settings.cache_data_format)
    folder = os.path.join(cache_folder(obj), "data")
    if pattern is None or not os.path.isdir(folder):
        return []
    prefix, suffix = pattern.split("{", 1)[0], pattern.rsplit("}", 1)[1]
    offset = cache_frame(obj, 0) * -1  # the scene frame of cache frame 0
    frames = []
    for name in os.listdir(folder):
        number = name[len(prefix):len(name) - len(suffix)]
        if name.startswith(prefix) and name.endswith(suffix) and number.lstrip("-").isdigit():
            frames.append(int(number) + offset)
    return sorted(frames)


def read_particles(obj, scene_frame, api):
    """(positions (N, 3) float32 in world space, attributes, what was read, the reader's Particles) of the frame."""
    path = particle_file(obj, scene_frame)
    particles = api.read_particles(path)
    positions = np.ascontiguousarray(particles.positions, dtype=np.float32)
    if len(positions) == 0:
        raise DomainError(f"'{obj.name}' has no liquid particles at cache frame {cache_frame(obj, scene_frame)}: "
                          f"{path}")
    return positions, dict(particles.attributes), f"fluid cache {os.path.basename(path)}", particles


def gravity_direction(obj, scene):
    """World direction gravity pulls the liquid: the scene's gravity when it is on (as Mantaflow takes it), else
    the domain's own. The narrow-band fill needs a down direction: none is an error in the artist's terms."""
    settings = domain_settings(obj)
    vector = np.array(scene.gravity if scene.use_gravity else settings.gravity, dtype=np.float64)
    length = np.linalg.norm(vector)
    if not length > 0:
        where = "Scene Properties > Gravity" if scene.use_gravity else "the domain's Gravity (scene gravity is off)"
        raise DomainError(f"'{obj.name}' has no gravity ({where}): filling the liquid under its band of particles "
                          "needs to know which way is down")
    return list(vector / length)


def _is_collision_effector(obj):
    for modifier in obj.modifiers:
        if modifier.type == "FLUID" and modifier.fluid_type == "EFFECTOR":
            effector = modifier.effector_settings
            return effector.effector_type == "COLLISION" and effector.use_effector
    return False


def obstacle_triangles(obj, scene, depsgraph=None):
    """The domain's collision effectors (its Effector collection if set, else the scene's) as world-space triangle
    soups, evaluated at the current frame when a depsgraph is given: 9 floats per triangle."""
    settings = domain_settings(obj)
    candidates = settings.effector_group.all_objects if settings.effector_group else scene.objects
    obstacles = []
    for candidate in candidates:
        if candidate == obj or candidate.type != "MESH" or not _is_collision_effector(candidate):
            continue
        evaluated = candidate.evaluated_get(depsgraph) if depsgraph is not None else candidate
        mesh = evaluated.to_mesh()
        try:
            mesh.calc_loop_triangles()
            count = len(mesh.vertices)
            vertices = np.empty(count * 3, dtype=np.float64)
            mesh.vertices.foreach_get("co", vertices)
            corners = np.empty(len(mesh.loop_triangles) * 3, dtype=np.int32)
            mesh.loop_triangles.foreach_get("vertices", corners)
        finally:
            evaluated.to_mesh_clear()
        matrix = np.array(evaluated.matrix_world, dtype=np.float64)
        world = vertices.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
        if len(corners):
            obstacles.append(world[corners].astype(np.float32).reshape(-1).tolist())
    return obstacles


def fluid_domain(obj, scene, depsgraph=None, placement=None):
    """The fluid domain for the core's narrow-band fill (the keys of FluidDomain, native/core/sph/fluid_domain.h):
    the grid's placement (origin, axes, resolution) as the reader found it in the cache's config, and what only the
    domain's settings say: which borders are walls, gravity, how deep the band of particles reaches, obstacles."""
    settings = domain_settings(obj)
    domain = dict(placement or {})
    domain.update(
        closed_borders=[bool(getattr(settings, f"use_collision_border_{side}")) for side in _BORDERS],
        gravity=gravity_direction(obj, scene),
        band_width_cells=float(settings.particle_band_width),
        obstacles=obstacle_triangles(obj, scene, depsgraph),
    )
    return domain


def cell_size(obj):
    """Mantaflow's cell: the domain's longest world-space side over its resolution divisions."""
    return max(_domain_size(obj)) / domain_settings(obj).resolution_max


def _domain_size(obj):
    # The domain mesh's own bounds, scaled: obj.dimensions follows the evaluated domain, which after a bake is
    # Mantaflow's liquid surface, not the box the grid fills.
    count = len(obj.data.vertices)
    if count == 0:
        raise DomainError(f"'{obj.name}': the domain mesh has no vertices, so it has no size")
    corners = np.empty(count * 3, dtype=np.float64)
    obj.data.vertices.foreach_get("co", corners)
    corners = corners.reshape(-1, 3)
    scale = np.linalg.norm(np.array(obj.matrix_world, dtype=np.float64)[:3, :3], axis=0)
    return np.ptp(corners, axis=0) * scale


def derived_radius(obj):
    """(particle radius, how it was derived): Mantaflow seeds Particle Sampling particles per cell along each axis,
    so they are a cell / sampling apart; a radius of that spacing (times the domain's Particle Radius factor) lets
    their spheres meet, as Mantaflow's own mesh assumes."""
    settings = domain_settings(obj)
    cell = cell_size(obj)
    radius = cell / settings.particle_number * settings.particle_radius
    how = (f"cell {cell:.4g} m ({max(_domain_size(obj)):.3g} m / Resolution {settings.resolution_max}) / Particle "
           f"Sampling {settings.particle_number} x Particle Radius {settings.particle_radius:g}")
    return radius, how


def describe(obj):
    """Lines for the panel: what the surface reads and what its defaults were derived from."""
    try:
        radius, how = derived_radius(obj)
    except DomainError as error:  # drawn on every redraw: a message, never an exception
        return [str(error)]
    settings = domain_settings(obj)
    return [f"Particles from the cache: {cache_folder(obj)}",
            f"Radius {radius:.4g} m = {how}",
            f"Particles kept {settings.particle_band_width:g} cells under the surface (Narrow Band Width)"]


def configure_surface(settings, obj):
    """A new surface's defaults for a liquid domain: the radius derived from its grid, and the iso threshold that
    puts the surface where Mantaflow's own mesh is. Lengths in radii (smoothing length, cube size) follow the
    radius."""
    settings.particle_radius = derived_radius(obj)[0]
    settings.iso_threshold = MANTAFLOW_ISO_THRESHOLD


def liquid_domain_for(context):
    """The liquid domain a "Surface From Fluid Domain" means: the active object if it is one, else the scene's only
    one; None when there is none or the choice is not clear."""
    if is_liquid_domain(context.active_object):
        return context.active_object
    domains = [obj for obj in context.scene.objects if is_liquid_domain(obj)]
    return domains[0] if len(domains) == 1 else None


def core_fills_narrow_band(api):
    """Whether this build's reconstruct takes a fluid domain (the narrow-band fill)."""
    import inspect
    try:
        return "fluid_domain" in inspect.signature(api.reconstruct).parameters
    except (TypeError, ValueError):
        return False
