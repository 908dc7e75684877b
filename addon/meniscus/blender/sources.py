"""Live sources: the particles of another object, as evaluated at the current frame.

What counts as particles, in order: the alive particles of the object's particle systems; else the points of a
point cloud; else the vertices of its evaluated mesh (modifiers and geometry nodes applied, so a Geometry Nodes
simulation that outputs points as vertices works too). Positions are in world space, like the surface object
(which the add operator leaves at the origin). A Mantaflow liquid domain is read from its cache (fluid_domain).

Never a wrong surface in silence: an object with particle systems is read from them even when none is alive now
(not from its mesh), and a mesh with faces is refused: its vertices are the corners of a surface, not particles.
"""
import hashlib

import bpy
import numpy as np

# Particle.alive_state as foreach_get reports it (DNA: PARS_UNEXIST 0, DEAD 1, UNBORN 2, ALIVE 3, DYING 4).
_PARTICLE_ALIVE, _PARTICLE_DYING = 3, 4


def digest(positions):
    """A short fingerprint of the positions: equal fingerprints mean nothing moved, so no rebuild is needed."""
    return hashlib.blake2b(np.ascontiguousarray(positions).tobytes(), digest_size=16).hexdigest()


def evaluated(obj, depsgraph):
    """The object as evaluated (modifiers, shape keys, geometry nodes): what a frame change and a bake read. Without
    a depsgraph (render_pre, a file just loaded, holding an earlier frame) the context's, so that every caller sees
    the same geometry (a fluid domain's obstacles enter its surface's playback key and bake record)."""
    if depsgraph is None:
        try:
            depsgraph = bpy.context.evaluated_depsgraph_get()
        except Exception:  # no context (render thread, some handlers): the unevaluated object is the best we have
            return obj
    try:
        return obj.evaluated_get(depsgraph)
    except Exception:
        return obj


def _particle_systems(evaluated):
    positions, velocities = [], []
    for system in evaluated.particle_systems:
        particles = system.particles
        count = len(particles)
        if count == 0:
            continue
        location = np.empty(count * 3, dtype=np.float32)
        particles.foreach_get("location", location)
        velocity = np.empty(count * 3, dtype=np.float32)
        particles.foreach_get("velocity", velocity)
        state = np.empty(count, dtype=np.int32)
        particles.foreach_get("alive_state", state)
        alive = (state == _PARTICLE_ALIVE) | (state == _PARTICLE_DYING)
        positions.append(location.reshape(-1, 3)[alive])
        velocities.append(velocity.reshape(-1, 3)[alive])
    if not positions:
        return None
    return np.concatenate(positions), {"velocity": np.concatenate(velocities)}


def _point_attributes(attributes, count, wanted):
    """Point-domain float attributes of the source the user asked for, plus 'velocity' when present."""
    found = {}
    for name in {"velocity", "v", *wanted}:
        attribute = attributes.get(name)
        if attribute is None or attribute.domain != "POINT" or len(attribute.data) != count:
            continue
        if attribute.data_type == "FLOAT":
            values = np.empty(count, dtype=np.float32)
            attribute.data.foreach_get("value", values)
        elif attribute.data_type == "FLOAT_VECTOR":
            values = np.empty(count * 3, dtype=np.float32)
            attribute.data.foreach_get("vector", values)
            values = values.reshape(-1, 3)
        else:
            continue
        found[name] = values
    return found


def _to_world(points, matrix):
    matrix = np.array(matrix, dtype=np.float64)
    return (points @ matrix[:3, :3].T + matrix[:3, 3]).astype(np.float32)


def _to_world_vectors(vectors, matrix):
    # Velocities rotate and scale with the object but do not translate.
    return (vectors @ np.array(matrix, dtype=np.float64)[:3, :3].T).astype(np.float32)


def object_particles(source, depsgraph=None, wanted=()):
    """(positions (N, 3) float32 in world space, attributes by name, a word for what was read)."""
    source_evaluated = evaluated(source, depsgraph)
    if len(source_evaluated.particle_systems):
        from_systems = _particle_systems(source_evaluated)
        kind = f"{len(source.particle_systems)} particle system(s)"
        if from_systems is None:  # none born yet or all dead: the emitter's own mesh is not the fluid
            return np.empty((0, 3), dtype=np.float32), {}, kind
        positions, attributes = from_systems
        return np.ascontiguousarray(positions), attributes, kind

    data = source_evaluated.data
    matrix = source_evaluated.matrix_world
    if source.type == "POINTCLOUD":
        count = len(data.points)
        flat = np.empty(count * 3, dtype=np.float32)
        data.attributes["position"].data.foreach_get("vector", flat)
        kind = "point cloud"
    elif source.type == "MESH":
        if len(data.polygons):
            raise ValueError(f"'{source.name}' is a mesh with {len(data.polygons):,} faces: its {len(data.vertices):,} "
                             "vertices are the corners of a surface, not particles. Surface a particle system, a "
                             "point cloud or a mesh of loose vertices")
        count = len(data.vertices)
        flat = np.empty(count * 3, dtype=np.float32)
        data.vertices.foreach_get("co", flat)
        kind = "mesh vertices"
    else:
        raise ValueError(f"'{source.name}' is a {source.type.lower()}: use a mesh, a point cloud or particles")
    attributes = _point_attributes(data.attributes, count, wanted)
    for name, values in attributes.items():
        if values.ndim == 2 and name in ("velocity", "v"):
            attributes[name] = _to_world_vectors(values, matrix)
    return np.ascontiguousarray(_to_world(flat.reshape(-1, 3), matrix)), attributes, kind
