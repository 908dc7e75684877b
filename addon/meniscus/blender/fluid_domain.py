"""A Mantaflow liquid domain (Blender's fluid simulation) as a source: the frame's FLIP particles come from the
domain's cache files through the core's reader, never from what the domain shows. The evaluated domain is the wrong
thing to read: hidden from renders or outside the bake it is its box (8 corners), with FLIP display off it is
Mantaflow's own surface, and its particle system follows the display amount.

Also here: the fluid domain the core's narrow-band fill needs (walls, gravity, band depth, obstacles; the grid's
placement comes from the cache's config through the reader), and the defaults derived from the domain's grid.
"""
import hashlib
import os

import bpy
import numpy as np
from mathutils import Euler, Matrix, Quaternion, Vector

from . import sources

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


def has_frame(obj, scene_frame):
    """Whether the domain's cache holds the particles of a scene frame."""
    try:
        particle_file(obj, scene_frame)
        return True
    except DomainError:
        return False


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


class DomainFrame:
    """What a domain gives for one frame: the particles (world space, where the domain is now), the fluid domain for
    the fill (None without one) and a digest of everything besides the particles that shapes the surface: the fill's
    domain (its settings, placement, the domain's matrix, obstacles at the cache frame) and the particle file's
    identity. Equal digests and positions mean the same surface; the playback key carries it."""

    def __init__(self, positions, attributes, kind, path, domain):
        self.positions, self.attributes, self.kind, self.path, self.domain = positions, attributes, kind, path, domain
        self.digest = fill_digest(domain, path)


def read_frame(obj, scene, scene_frame, api, depsgraph=None, with_fill=True):
    """The DomainFrame of a scene frame (main thread only: it evaluates the domain and its obstacles); raises
    DomainError when the cache cannot give it."""
    path = particle_file(obj, scene_frame)
    given = domain_arguments(obj, scene, scene_frame, depsgraph)
    particles = api.read_particles(path)
    if len(particles.positions) == 0:
        raise DomainError(f"'{obj.name}' has no liquid particles at cache frame {cache_frame(obj, scene_frame)}: "
                          f"{path}")
    positions, attributes, arguments = placed(particles, {"fluid_domain": given}, with_fill)
    return DomainFrame(positions, attributes, f"fluid cache {os.path.basename(path)}", path,
                       arguments.get("fluid_domain"))


def domain_arguments(obj, scene, scene_frame, depsgraph=None):
    """What the main thread gives the fill of a scene frame: the domain's settings, its obstacles where they were at
    the cache frame and the domain's matrix at the scene frame; the cache file adds the grid's placement (placed)."""
    return fluid_domain(obj, scene, depsgraph, frame=cache_frame(obj, scene_frame), scene_frame=int(round(scene_frame)))


# Attribute names of velocities, which turn with a moved domain (the readers' and Houdini's names).
_VELOCITY_NAMES = ("velocity", "v", "vel", "Velocity")


def _moved(then, now):
    """The world transform from where the domain was simulated to where it is now (4 x 4), None when it has not
    moved. Both matrices column-major, as Blender and the cache's config keep them."""
    if then is None or now is None:
        return None
    then = np.asarray(then, dtype=np.float64).reshape(4, 4).T
    now = np.asarray(now, dtype=np.float64).reshape(4, 4).T
    if np.allclose(then, now, rtol=1e-6, atol=1e-6 * max(1.0, np.abs(then).max())):  # the same floats, read back
        return None
    return now @ np.linalg.inv(then)


def placed(particles, arguments, with_fill=True):
    """(positions, attributes, reconstruct's arguments) of a frame read from a domain's cache; bpy-free (a bake runs
    it in its thread). The reader places the particles and the grid where the domain was when the frame was
    simulated; Blender shows a baked liquid where the domain object is now (its fluid mesh follows the object), so a
    domain moved, turned or scaled since is followed: the particles, their velocities, the grid, the fill's down and
    the obstacles (taken, as always, as where they were when the frame was simulated: the fill happens as the liquid
    was simulated and the result follows the domain). arguments["fluid_domain"] is what the main thread gave
    (domain_arguments); the file's placement completes it."""
    given = arguments["fluid_domain"]
    read = getattr(particles, "fluid_domain", None) or {}
    positions = np.ascontiguousarray(particles.positions, dtype=np.float32)
    attributes = dict(particles.attributes)
    domain = {**read, **given}
    move = _moved(read.get("object_to_world"), given.get("object_to_world"))
    if move is not None:
        linear, shift = move[:3, :3], move[:3, 3]
        positions = np.ascontiguousarray(positions @ linear.T + shift, dtype=np.float32)
        for name in _VELOCITY_NAMES:
            if name in attributes and np.ndim(attributes[name]) == 2:
                attributes[name] = np.ascontiguousarray(np.asarray(attributes[name]) @ linear.T, dtype=np.float32)
        if "origin" in domain:
            domain["origin"] = (linear @ np.asarray(domain["origin"], dtype=np.float64) + shift).tolist()
        if "axes" in domain:
            domain["axes"] = (np.asarray(domain["axes"], dtype=np.float64) @ linear.T).tolist()
        domain["obstacles"] = [(np.asarray(soup, dtype=np.float64).reshape(-1, 3) @ linear.T + shift)
                               .astype(np.float32).reshape(-1).tolist() for soup in domain.get("obstacles", [])]
        down = linear @ np.asarray(domain["gravity"], dtype=np.float64)
        domain["gravity"] = (down / np.linalg.norm(down)).tolist()
    if not with_fill:
        return positions, attributes, {key: value for key, value in arguments.items() if key != "fluid_domain"}
    return positions, attributes, {**arguments, "fluid_domain": domain}


def fill_digest(domain, path):
    """A fingerprint of the fill's domain (None: no fill) and of the particle file's path, size and modification
    time: a changed border, band width, obstacle, gravity or cache folder changes it without a frame change."""
    digest = hashlib.blake2b(digest_size=16)
    stat = os.stat(path)
    digest.update(f"{path}|{stat.st_size}|{stat.st_mtime_ns}".encode())
    for key in sorted(domain or {}):
        value = domain[key]
        if key == "obstacles":
            for soup in value:
                digest.update(b"|obstacle:" + np.ascontiguousarray(soup, dtype=np.float32).tobytes())
        else:
            digest.update(f"|{key}:{np.asarray(value, dtype=np.float64).tolist()!r}".encode())
    return digest.hexdigest()


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


def obstacle_among(obj, objects):
    """Whether one of `objects` (those a depsgraph update changed) is a collision effector that a liquid domain obj's
    fill may use: moving an obstacle changes the fill without touching the domain."""
    return is_liquid_domain(obj) and any(other != obj and other.type == "MESH" and _is_collision_effector(other)
                                         for other in objects)


# The transform channels an object's F-curves may animate (Blender's object matrix is made of these alone when no
# constraint, driver or NLA strip takes part).
_TRANSFORM_PATHS = ("location", "rotation_euler", "rotation_quaternion", "rotation_axis_angle", "scale",
                    "delta_location", "delta_rotation_euler", "delta_rotation_quaternion", "delta_scale")


def _fcurves(obj):
    animation = obj.animation_data
    if animation is None or animation.action is None:
        return []
    if hasattr(animation, "action_slot"):  # Blender 4.4+: a layered action keeps each object's F-curves in a slot
        slot = animation.action_slot
        if slot is None:  # an action assigned without a slot animates nothing (5.x actions have no .fcurves)
            return []
        from bpy_extras import anim_utils
        channels = anim_utils.action_get_channelbag_for_slot(animation.action, slot)
        return list(channels.fcurves) if channels is not None else []
    return list(animation.action.fcurves)


def _animated(obj):
    """Whether obj (or a parent) moves with the frame at all."""
    while obj is not None:
        animation = obj.animation_data
        if len(obj.constraints) or (animation is not None and (animation.action is not None or
                                                              len(animation.drivers) or len(animation.nla_tracks))):
            return True
        obj = obj.parent
    return False


def _not_from_fcurves(obj):
    """What keeps obj's matrix at another frame from being evaluated from its own and its parents' F-curves."""
    while obj is not None:
        animation = obj.animation_data
        if len(obj.constraints):
            return f"'{obj.name}' has constraints"
        if animation is not None and (len(animation.drivers) or len(animation.nla_tracks)):
            return f"'{obj.name}' is animated by drivers or NLA strips"
        if obj.parent is not None and obj.parent_type != "OBJECT":
            return f"'{obj.name}' has a {obj.parent_type.lower()} parent"
        obj = obj.parent
    return ""


def _matrix_at(obj, frame):
    """obj's world matrix at a frame, from the F-curves of its transform channels and of its parents' (as Blender
    composes them: location + delta, delta rotation after rotation, scale x delta scale)."""
    values = {path: list(getattr(obj, path)) for path in _TRANSFORM_PATHS}
    for curve in _fcurves(obj):
        channel = values.get(curve.data_path)
        if channel is not None and not curve.mute and 0 <= curve.array_index < len(channel):
            channel[curve.array_index] = curve.evaluate(frame)
    mode = obj.rotation_mode
    if mode == "QUATERNION":
        rotation = (Quaternion(values["delta_rotation_quaternion"]).normalized().to_matrix() @
                    Quaternion(values["rotation_quaternion"]).normalized().to_matrix())
    elif mode == "AXIS_ANGLE":
        angle, *axis = values["rotation_axis_angle"]
        rotation = Matrix.Rotation(angle, 3, Vector(axis))
    else:
        rotation = (Euler(values["delta_rotation_euler"], mode).to_matrix() @
                    Euler(values["rotation_euler"], mode).to_matrix())
    scale = [a * b for a, b in zip(values["scale"], values["delta_scale"])]
    basis = rotation @ Matrix.Diagonal(scale)
    basis = basis.to_4x4()
    basis.translation = [a + b for a, b in zip(values["location"], values["delta_location"])]
    if obj.parent is not None:
        return _matrix_at(obj.parent, frame) @ obj.matrix_parent_inverse @ basis
    return basis


def _matrix_at_frame(obj, evaluated, scene, frame, role):
    """Where obj was at a scene frame (4 x 4): as evaluated when that is the current frame or it does not move, else
    from its F-curves; refused (DomainError) when constraints, drivers or NLA move it."""
    if frame == scene.frame_current or not _animated(obj):
        return np.array(evaluated.matrix_world, dtype=np.float64)
    problem = _not_from_fcurves(obj)
    if problem:
        raise DomainError(f"{role} '{obj.name}' cannot be placed at frame {frame} (the scene is at frame "
                          f"{scene.frame_current}): {problem} (set the domain's Frame Offset to 0, or key its motion)")
    return np.array(_matrix_at(obj, frame), dtype=np.float64)


def obstacle_triangles(obj, scene, depsgraph=None, frame=None):
    """The domain's collision effectors (its Effector collection if set, else the scene's) as world-space triangle
    soups, placed where they were at `frame` (the cache frame: where Mantaflow had them when it simulated that
    frame; default the current frame), their shape as evaluated now: 9 floats per triangle."""
    settings = domain_settings(obj)
    candidates = settings.effector_group.all_objects if settings.effector_group else scene.objects
    frame = scene.frame_current if frame is None else frame
    obstacles = []
    for candidate in candidates:
        if candidate == obj or candidate.type != "MESH" or not _is_collision_effector(candidate):
            continue
        evaluated = sources.evaluated(candidate, depsgraph)
        matrix = _matrix_at_frame(candidate, evaluated, scene, frame, "Obstacle")
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
        world = vertices.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
        if len(corners):
            obstacles.append(world[corners].astype(np.float32).reshape(-1).tolist())
    return obstacles


def fluid_domain(obj, scene, depsgraph=None, placement=None, frame=None, scene_frame=None):
    """The fluid domain for the core's narrow-band fill (the keys of FluidDomain, native/core/sph/fluid_domain.h):
    the grid's placement (origin, axes, resolution) as the reader found it in the cache's config, and what only the
    domain's settings say: which borders are walls, gravity, how deep the band of particles reaches, obstacles (where
    they were at `frame`, the cache frame; default the current frame), the domain object's matrix at
    `scene_frame` (default the current frame; column-major, as the cache's config keeps it) and the Mesh panel's
    settings (Upres Factor, particle radius, smoothing, concavity)."""
    settings = domain_settings(obj)
    scene_frame = scene.frame_current if scene_frame is None else scene_frame
    evaluated = sources.evaluated(obj, depsgraph)
    matrix = _matrix_at_frame(obj, evaluated, scene, scene_frame, "Fluid domain")
    domain = dict(placement or {})
    domain.update(
        closed_borders=[bool(getattr(settings, f"use_collision_border_{side}")) for side in _BORDERS],
        gravity=gravity_direction(obj, scene),
        band_width_cells=float(settings.particle_band_width),
        obstacles=obstacle_triangles(obj, scene, depsgraph, frame),
        object_to_world=matrix.T.reshape(-1).tolist(),
        # The Mesh panel's settings, for Mantaflow's own surface (Fluid Surface automatic or 1).
        mesh_upres=int(settings.mesh_scale),
        mesh_particle_radius=float(settings.mesh_particle_radius),
        mesh_smoothen_pos=int(settings.mesh_smoothen_pos),
        mesh_smoothen_neg=int(settings.mesh_smoothen_neg),
        mesh_concave_lower=float(settings.mesh_concave_lower),
        mesh_concave_upper=float(settings.mesh_concave_upper),
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
