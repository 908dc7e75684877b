"""Where a ~1 M-triangle mesh write spends its time in Blender, step by step, and the depsgraph evaluation after it.

    /usr/bin/python3 bench/blender_mesh_write_profile.py --prepare        # once: the two surfaces (core, Python 3.11)
    blender -b --factory-startup --python-exit-code 1 --python bench/blender_mesh_write_profile.py -- \
        --json build/bench/mesh_write_profile_3.4.json
    build/venv/bpy-5.2/bin/python bench/blender_mesh_write_profile.py -- --json build/bench/mesh_write_profile_5.2.json
    /usr/bin/python3 bench/blender_mesh_write_profile.py --report build/bench/mesh_write_profile_*.json
    bash bench/blender_mesh_write_profile.sh                              # all of the above, every Blender found

Surfaces (--prepare, cached in build/bench/mesh_write_profile/): frames 1 and 2 of bench/blender_frame_change.py's
input (jittered pentagonal_hexecontahedron_32286_particles.bgeo with a `velocity` attribute) reconstructed with the
add-on's default pipeline at cube size 0.57, as that benchmark does: ~991 000 triangles, ~495 000 vertices, normals
and velocity, saved as .npz so that every Blender (also 5.2 on Python 3.13, for which no core is built) writes the
same arrays. Writes alternate between the two frames, so every write changes the topology as a frame change does.

Only the module is needed in Blender: addon/meniscus/blender/mesh_update.py is loaded from --addon-path by file
(it imports bpy and numpy only), so the core need not exist for the running Python.

Measured on one reused Mesh linked to the scene, median of --repeat writes per path (after one untimed write):
  before  the write of main before this change (frozen copy below: foreach_set with int32 indices, `use_smooth`
          written, `update(calc_edges=True)`), each step timed inline;
  after   mesh_update.write_surface itself, its steps timed by wrapping the module's step functions;
both with custom normals (the add-on's default) and without. Then
  eval       view_layer.update() right after the write: the depsgraph evaluation a frame change pays;
  next eval  the mesh tagged (update_tag) and evaluated again without a change: what custom normals cost at every
             later evaluation (3.4 recomputes split normals);
  normals    the evaluated mesh's shading normals read back (corner_normals on 4.1+, calc_normals_split on 3.4): what
  read       a viewport or renderer asks for later (informative, not in the frame change).
Alternatives: single operations on a written mesh (median of --repeat), to show why each step is done the way it is.
"""
import argparse
import importlib.util
import json
import os
import pathlib
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
CACHE = ROOT / "build" / "bench" / "mesh_write_profile"
SURFACES = [CACHE / f"surface_{frame}.npz" for frame in (1, 2)]
RESULTS = ROOT / "bench" / "results" / "blender_mesh_write_profile"
CUBE_SIZE = 0.57


# ---- the surfaces (plain Python with the core) ----------------------------------------------------------------------

def prepare(addon_path):
    import numpy as np

    sys.path.insert(0, str(ROOT / "bench"))
    sys.path.insert(0, os.path.abspath(addon_path))
    import blender_frame_change
    from meniscus import cache

    if all(path.is_file() for path in SURFACES):
        print(f"surfaces already in {CACHE}")
        return
    paths = blender_frame_change.prepare_frames()
    # The add-on's defaults, as bench/blender_frame_change.py sets them (update.reconstruction_arguments).
    arguments = dict(particle_radius=blender_frame_change.RADIUS, smoothing_length=2.0, cube_size=CUBE_SIZE,
                     iso_threshold=0.6, mesh_cleanup=False, mesh_cleanup_snap_distance=-1.0, decimate_barnacles=True,
                     smoothing_iterations=25, smoothing_strength=1.0, smoothing_weights=True, weights_normalization=0.0,
                     volume_restoration=True, output_weights=False, normals=True, normal_smoothing_iterations=10,
                     sph_normals=False, threads=0, memory_budget=0)
    CACHE.mkdir(parents=True, exist_ok=True)
    for path, target in zip(paths, SURFACES):
        mesh = cache.reconstruct_file(str(path), arguments, ["velocity"]).mesh
        np.savez(target, vertices=mesh.vertices, triangles=mesh.triangles, normals=mesh.normals,
                 velocity=mesh.attributes["velocity"])
        print(f"wrote {target}: {len(mesh.vertices)} vertices, {len(mesh.triangles)} triangles")


# ---- in Blender ---------------------------------------------------------------------------------------------------

def load_module(addon_path):
    path = pathlib.Path(addon_path) / "meniscus" / "blender" / "mesh_update.py"
    spec = importlib.util.spec_from_file_location("meniscus_mesh_update_profiled", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Clock:
    """Sums seconds per step name."""

    def __init__(self):
        self.seconds = {}

    def add(self, name, seconds):
        self.seconds[name] = self.seconds.get(name, 0.0) + seconds

    def run(self, name, function, *args, **kwargs):
        started = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            self.add(name, time.perf_counter() - started)


def write_before(mesh, surface, with_normals, clock, version):
    """The write of main before this change (addon/meniscus/blender/mesh_update.py at d6e8eeb), step by step."""
    import numpy as np

    vertices, triangles, normals, velocity = surface
    vertex_count, triangle_count = len(vertices), len(triangles)
    clock.run("clear_geometry", mesh.clear_geometry)
    clock.run("vertices", lambda: (mesh.vertices.add(vertex_count),
                                   mesh.vertices.foreach_set("co", np.ascontiguousarray(vertices, np.float32).reshape(-1))))
    clock.run("corners", lambda: (mesh.loops.add(3 * triangle_count),
                                  mesh.loops.foreach_set("vertex_index",
                                                         np.ascontiguousarray(triangles, np.int32).reshape(-1))))

    def faces():
        mesh.polygons.add(triangle_count)
        mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * triangle_count, 3, dtype=np.int32))
        if version < (4, 0, 0):
            mesh.polygons.foreach_set("loop_total", np.full(triangle_count, 3, dtype=np.int32))

    clock.run("faces", faces)
    clock.run("use_smooth", mesh.polygons.foreach_set, "use_smooth", np.ones(triangle_count, dtype=bool))
    clock.run("edges (update(calc_edges=True))", mesh.update, calc_edges=True)

    def attribute():
        attribute = mesh.attributes.get("velocity") or mesh.attributes.new("velocity", "FLOAT_VECTOR", "POINT")
        attribute.data.foreach_set("vector", np.ascontiguousarray(velocity, np.float32).reshape(-1))

    clock.run("point attributes", attribute)

    def custom_normals():
        if with_normals and version >= (4, 5, 0):
            attribute = mesh.attributes.get("custom_normal") or mesh.attributes.new("custom_normal", "FLOAT_VECTOR",
                                                                                    "POINT")
            attribute.data.foreach_set("vector", np.ascontiguousarray(normals, np.float32).reshape(-1))
        elif with_normals:
            if version < (4, 1, 0):
                mesh.use_auto_smooth = True
                mesh.auto_smooth_angle = np.pi
            mesh.normals_split_custom_set_from_vertices(np.ascontiguousarray(normals, dtype=np.float32))
        elif version < (4, 1, 0):
            mesh.use_auto_smooth = False

    clock.run("custom normals", custom_normals)


AFTER_STEPS = {  # mesh_update's step functions -> the step they stand for in the table
    "_write_vertices": "vertices",
    "_write_faces": "corners + faces (+ use_smooth on 3.4)",
    "_mesh_arrays": "corners, faces, edges: made by the core",
    "_write_edges": "edges: written",
    "_write_point_attribute": "point attributes",
    "_write_custom_normals": "custom normals",
}


def write_after(module, mesh, surface, with_normals, clock):
    vertices, triangles, normals, velocity = surface
    originals = {name: getattr(module, name) for name in AFTER_STEPS}

    def timed(name):
        original = originals[name]
        return lambda *args, **kwargs: clock.run(AFTER_STEPS[name], original, *args, **kwargs)

    for name in AFTER_STEPS:
        setattr(module, name, timed(name))
    try:
        started = time.perf_counter()
        module.write_surface(mesh, vertices, triangles, normals if with_normals else None, {"velocity": velocity})
        total = time.perf_counter() - started
    finally:
        for name, original in originals.items():
            setattr(module, name, original)
    clock.add("clear_geometry + update() + rest", total - sum(clock.seconds.values()))


def measure_path(bpy, module, obj, surfaces, path, with_normals, repeat, version):
    """Medians of each step over `repeat` writes (after one untimed write), plus eval, next eval and normals read."""
    import numpy as np

    runs = []
    for index in range(repeat + 1):
        surface = surfaces[index % 2]
        clock = Clock()
        started = time.perf_counter()
        if path == "before":
            write_before(obj.data, surface, with_normals, clock, version)
        else:
            write_after(module, obj.data, surface, with_normals, clock)
        clock.seconds["write"] = time.perf_counter() - started
        clock.run("eval", bpy.context.view_layer.update)
        clock.seconds["write + eval"] = clock.seconds["write"] + clock.seconds["eval"]
        obj.data.update_tag()
        clock.run("next eval", bpy.context.view_layer.update)
        evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
        shading = clock.run("normals read", module.read_corner_normals, evaluated)
        if index > 0:
            runs.append(clock.seconds)
        last = (surface, shading)
    # The last write's shading normals against the core's (1.0000: custom normals in effect).
    (vertices, triangles, normals, _), shading = last
    agreement = float(np.mean(np.einsum("ij,ij->i", shading, normals[triangles.reshape(-1)])))
    steps = list(runs[0])
    return {"steps": {step: statistics.median(run[step] for run in runs) for step in steps},
            "mean_dot_with_core_normals": agreement, "validate_changed": bool(obj.data.validate()),
            "runs": runs}


def timed_median(function, repeat, setup=None):
    seconds = []
    for _ in range(repeat):
        if setup is not None:
            setup()
        started = time.perf_counter()
        function()
        seconds.append(time.perf_counter() - started)
    return statistics.median(seconds)


def measure_alternatives(bpy, module, obj, surfaces, repeat, version):
    """Single operations on a mesh written by mesh_update (same sizes), timed on their own."""
    import numpy as np

    mesh = obj.data
    vertices, triangles, normals, velocity = surfaces[0]
    module.write_surface(mesh, vertices, triangles, None, {"velocity": velocity})
    bpy.context.view_layer.update()
    flat_vertices = np.ascontiguousarray(vertices, np.float32).reshape(-1)
    corners = np.ascontiguousarray(triangles, np.int32).reshape(-1)
    starts = np.arange(0, len(corners), 3, dtype=np.int32)
    no_quads = np.zeros((0, 4), np.int32)
    edges, corner_edges = module._mesh_arrays(np.ascontiguousarray(triangles, np.int32), no_quads, len(vertices))[3]
    result = {}

    def add(name, function, setup=None):
        result[name] = timed_median(function, repeat, setup)

    add("vertices: foreach_set('co') float32", lambda: mesh.vertices.foreach_set("co", flat_vertices))
    if version >= (4, 0, 0):
        add("vertices: attributes['position'] float32",
            lambda: mesh.attributes["position"].data.foreach_set("vector", flat_vertices))
    add("corners: foreach_set('vertex_index') int32", lambda: mesh.loops.foreach_set("vertex_index", corners))
    add("corners: foreach_set('vertex_index') uint32",
        lambda: mesh.loops.foreach_set("vertex_index", corners.view(np.uint32)))
    if version >= (4, 0, 0):
        add("corners: attributes['.corner_vert'] int32",
            lambda: mesh.attributes[".corner_vert"].data.foreach_set("value", corners))
    add("faces: foreach_set('loop_start') int32", lambda: mesh.polygons.foreach_set("loop_start", starts))
    add("faces: foreach_set('loop_start') uint32",
        lambda: mesh.polygons.foreach_set("loop_start", starts.view(np.uint32)))
    if version < (4, 0, 0):
        totals = np.full(len(starts), 3, dtype=np.int32)
        add("faces: foreach_set('loop_total') int32", lambda: mesh.polygons.foreach_set("loop_total", totals))
        add("faces: foreach_set('loop_total') uint32",
            lambda: mesh.polygons.foreach_set("loop_total", totals.view(np.uint32)))
    add("faces: foreach_set('use_smooth') bool",
        lambda: mesh.polygons.foreach_set("use_smooth", np.ones(len(starts), dtype=bool)))
    if version >= (4, 0, 0):
        def remove_sharp_face():
            if "sharp_face" in mesh.attributes:
                mesh.attributes.remove(mesh.attributes["sharp_face"])

        add("faces: remove 'sharp_face' after a use_smooth write (4.0+: all smooth)", remove_sharp_face,
            setup=lambda: mesh.polygons.foreach_set("use_smooth", np.ones(len(starts), dtype=bool)))
    add("edges: update(calc_edges=True) (Blender's hash maps)", lambda: mesh.update(calc_edges=True))
    add("corners, faces, edges: made by the core (mesh_update._mesh_arrays)",
        lambda: module._mesh_arrays(np.ascontiguousarray(triangles, np.int32), no_quads, len(vertices)))
    add("edges: numpy argsort instead of the packed sort", lambda: _edges_by_argsort(triangles))
    add("edges: edges.foreach_set('vertices') int32",
        lambda: mesh.edges.foreach_set("vertices", edges.reshape(-1)))
    add("edges: edges.foreach_set('vertices') uint32",
        lambda: mesh.edges.foreach_set("vertices", edges.reshape(-1).view(np.uint32)))
    add("edges: loops.foreach_set('edge_index') int32", lambda: mesh.loops.foreach_set("edge_index", corner_edges))
    add("edges: loops.foreach_set('edge_index') uint32",
        lambda: mesh.loops.foreach_set("edge_index", corner_edges.view(np.uint32)))
    if version >= (4, 0, 0):
        add("edges: attributes['.edge_verts'] + ['.corner_edge'] int32",
            lambda: (mesh.attributes[".edge_verts"].data.foreach_set("value", edges.reshape(-1)),
                     mesh.attributes[".corner_edge"].data.foreach_set("value", corner_edges)))
    add("update() with edges present", mesh.update)
    # The whole geometry written twice without clear_geometry in between (equal counts: nothing to resize) against
    # clear_geometry + add: what keeping the arrays would save when a frame has the same counts as the last.
    add("clear_geometry (1 M-triangle mesh)", mesh.clear_geometry,
        setup=lambda: module.write_surface(mesh, vertices, triangles, None, None))

    # Custom normals: each way this version offers, its write and the evaluation after it.
    flat_normals = np.ascontiguousarray(normals, np.float32)
    options = []
    if version >= (4, 5, 0):
        def free_normals():
            attribute = mesh.attributes.get("custom_normal") or mesh.attributes.new("custom_normal", "FLOAT_VECTOR",
                                                                                    "POINT")
            attribute.data.foreach_set("vector", flat_normals.reshape(-1))

        options.append(("custom_normal point attribute (4.5+)", free_normals))

    def from_vertices():
        if version < (4, 1, 0):
            mesh.use_auto_smooth = True
            mesh.auto_smooth_angle = np.pi
        mesh.normals_split_custom_set_from_vertices(flat_normals)

    options.append(("normals_split_custom_set_from_vertices", from_vertices))
    corner_normals = np.ascontiguousarray(flat_normals[triangles.reshape(-1)])

    def per_corner():
        if version < (4, 1, 0):
            mesh.use_auto_smooth = True
            mesh.auto_smooth_angle = np.pi
        mesh.normals_split_custom_set(corner_normals)

    options.append(("normals_split_custom_set (per corner)", per_corner))

    def none():
        if version < (4, 1, 0):
            mesh.use_auto_smooth = False

    options.append(("none: Blender's own vertex normals", none))
    normals_rows = {}
    for name, function in options:
        writes, evaluations, next_evaluations, agreements = [], [], [], []
        for _ in range(max(3, repeat // 2)):
            module.write_surface(mesh, vertices, triangles, None, None)
            bpy.context.view_layer.update()
            started = time.perf_counter()
            function()
            writes.append(time.perf_counter() - started)
            started = time.perf_counter()
            bpy.context.view_layer.update()
            evaluations.append(time.perf_counter() - started)
            mesh.update_tag()
            started = time.perf_counter()
            bpy.context.view_layer.update()
            next_evaluations.append(time.perf_counter() - started)
        shading = module.read_corner_normals(obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data)
        dots = np.clip(np.einsum("ij,ij->i", shading, corner_normals), -1.0, 1.0)
        angles = np.degrees(np.arccos(dots))
        normals_rows[name] = {"write": statistics.median(writes), "eval": statistics.median(evaluations),
                              "next eval": statistics.median(next_evaluations),
                              "mean_dot": float(dots.mean()), "angle_p50": float(np.percentile(angles, 50)),
                              "angle_p99": float(np.percentile(angles, 99)), "angle_max": float(angles.max())}
    module.write_surface(mesh, vertices, triangles, None, None)
    return result, normals_rows


def _edges_by_argsort(triangles):
    import numpy as np

    corners = triangles.reshape(-1)
    following = triangles[:, [1, 2, 0]].reshape(-1)
    keys = (np.minimum(corners, following).astype(np.int64) << 32) | np.maximum(corners, following)
    order = np.argsort(keys)
    keys = keys[order]
    first = np.empty(len(keys), dtype=bool)
    first[0] = True
    np.not_equal(keys[1:], keys[:-1], out=first[1:])
    corner_edges = np.empty(len(keys), dtype=np.int32)
    corner_edges[order] = np.cumsum(first, dtype=np.int32) - 1
    return keys[first], corner_edges


def run_blender(arguments):
    import bpy
    import numpy as np

    as_module = not bpy.app.binary_path
    if as_module:  # what --factory-startup does for the executable
        bpy.ops.wm.read_factory_settings(use_empty=False)
    version = tuple(bpy.app.version)
    module = load_module(arguments.addon_path)
    surfaces = []
    for path in SURFACES:
        if not path.is_file():
            raise SystemExit(f"{path} missing: run /usr/bin/python3 {__file__} --prepare first")
        data = np.load(path)
        surfaces.append((data["vertices"], data["triangles"], data["normals"], data["velocity"]))
    print(f"Blender {bpy.app.version_string} (numpy {np.__version__}): "
          + ", ".join(f"{len(s[0])} vertices / {len(s[1])} triangles" for s in surfaces))

    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    mesh = bpy.data.meshes.new("profiled_surface")
    obj = bpy.data.objects.new("profiled_surface", mesh)
    bpy.context.scene.collection.objects.link(obj)

    record = {"blender": bpy.app.version_string, "numpy": np.__version__, "python": sys.version.split()[0],
              "repeat": arguments.repeat, "vertices": [len(s[0]) for s in surfaces],
              "triangles": [len(s[1]) for s in surfaces], "load_average_before": os.getloadavg(), "paths": {}}
    # Interleaved: before and after alternate per setting, so that a change in the machine's load hits both.
    for with_normals in (True, False):
        for path in ("before", "after"):
            key = f"{path}, custom normals {'on' if with_normals else 'off'}"
            result = measure_path(bpy, module, obj, surfaces, path, with_normals, arguments.repeat, version)
            record["paths"][key] = result
            steps = result["steps"]
            print(f"{key}: write {steps['write']:.3f} + eval {steps['eval']:.3f} = {steps['write + eval']:.3f} s; "
                  + ", ".join(f"{k} {v:.3f}" for k, v in steps.items() if k not in ("write", "eval", "write + eval"))
                  + f"; mean dot {result['mean_dot_with_core_normals']:.5f}")
            sys.stdout.flush()
    alternatives, normals_rows = measure_alternatives(bpy, module, obj, surfaces, arguments.repeat, version)
    record["alternatives"] = alternatives
    record["custom_normals"] = normals_rows
    for name, seconds in alternatives.items():
        print(f"  {name}: {seconds:.4f}")
    for name, row in normals_rows.items():
        print(f"  normals {name}: " + ", ".join(f"{k} {v:.4f}" for k, v in row.items()))
    record["load_average_after"] = os.getloadavg()
    if arguments.json:
        output = pathlib.Path(arguments.json)
        output.parent.mkdir(parents=True, exist_ok=True)
        output.write_text(json.dumps(record, indent=1))
        print(f"wrote {output}")
    sys.stdout.flush()
    sys.stderr.flush()
    if as_module:  # some bpy wheels crash while tearing down at interpreter exit (see tests/blender/_support.py)
        os._exit(0)


# ---- the report (plain Python) ------------------------------------------------------------------------------------

BEFORE_ROWS = ["clear_geometry", "vertices", "corners", "faces", "use_smooth", "edges (update(calc_edges=True))",
               "point attributes", "custom normals"]
AFTER_ROWS = ["vertices", "corners + faces (+ use_smooth on 3.4)", "edges: computed (numpy)", "edges: written",
              "clear_geometry + update() + rest", "point attributes", "custom normals"]
TOTAL_ROWS = ["write", "eval", "write + eval", "next eval", "normals read"]


def _cell(steps, row):
    return f"{steps[row]:.3f}" if row in steps else "–"


def write_report(json_paths, output=RESULTS):
    records = [json.loads(pathlib.Path(path).read_text()) for path in json_paths]
    records.sort(key=lambda record: [int(part) for part in record["blender"].split()[0].split(".")])
    lines = [
        "# Blender mesh write, step by step (~1 M triangles)", "",
        "`bench/blender_mesh_write_profile.py`: the ~991 k-triangle surfaces of frames 1 and 2 of the frame-change "
        "benchmark (add-on default pipeline, cube size 0.57, normals and a `velocity` point attribute), written "
        "alternately into one reused Mesh linked to the scene, so that every write changes the topology. Seconds, "
        f"**median of {records[0]['repeat']} writes** per path after one untimed write. *before* = the write of "
        "main before this change (int32 `foreach_set`, `use_smooth` written, `update(calc_edges=True)`); *after* = "
        "`mesh_update.write_surface` now. *eval* = `view_layer.update()` right after the write (what a frame change "
        "pays after the handler); *write + eval* = Blender's share of a frame change without the add-on's glue; "
        "*next eval* = the mesh tagged and evaluated again unchanged; *normals read* = the evaluated mesh's shading "
        "normals read back (what a viewport or renderer asks for later; informative). *n·n_core* = mean dot product "
        "of the shading normals with the core's (1.0000: custom normals in effect). 2 cores shared with another "
        "engineer's jobs (load averages below): compare columns within a table, before and after ran interleaved.",
        "",
    ]
    for record in records:
        paths = record["paths"]
        load = f"{record['load_average_before'][0]:.1f} → {record['load_average_after'][0]:.1f}"
        lines += [f"## Blender {record['blender']} (Python {record['python']}, numpy {record['numpy']}; "
                  f"load average {load})", ""]
        columns = list(paths)
        lines.append("| step | " + " | ".join(columns) + " |")
        lines.append("|---|" + "---:|" * len(columns))
        rows = []
        for row in BEFORE_ROWS:
            rows.append((f"before: {row}", row, "before"))
        for row in AFTER_ROWS:
            rows.append((f"after: {row}", row, "after"))
        for label, row, path in rows:
            cells = [(_cell(paths[column]["steps"], row) if column.startswith(path) else "") for column in columns]
            if any(cell not in ("", "–") for cell in cells):
                lines.append(f"| {label} | " + " | ".join(cells) + " |")
        for row in TOTAL_ROWS:
            bold = row in ("write", "write + eval")
            cells = [_cell(paths[column]["steps"], row) for column in columns]
            lines.append(f"| {'**' + row + '**' if bold else row} | "
                         + " | ".join(f"**{cell}**" if bold else cell for cell in cells) + " |")
        lines.append("| n·n_core | " + " | ".join(f"{paths[c]['mean_dot_with_core_normals']:.4f}" for c in columns)
                     + " |")
        lines.append("| validate() found something | " + " | ".join(str(paths[c]["validate_changed"]) for c in columns)
                     + " |")
        lines += ["", "Alternatives (one operation on a written 1 M-triangle mesh, median):", "",
                  "| operation | s |", "|---|---:|"]
        for name, seconds in record["alternatives"].items():
            lines.append(f"| {name} | {seconds:.4f} |")
        lines += ["", "Custom normals, each way this version offers (write, then the evaluation after it and a later "
                  "unchanged one; angles between the shading normals and the core's, degrees):", "",
                  "| way | write | eval | next eval | n·n_core | angle p50 | angle p99 | angle max |",
                  "|---|---:|---:|---:|---:|---:|---:|---:|"]
        for name, row in record["custom_normals"].items():
            lines.append(f"| {name} | {row['write']:.3f} | {row['eval']:.3f} | {row['next eval']:.3f} | "
                         f"{row['mean_dot']:.5f} | {row['angle_p50']:.2f} | {row['angle_p99']:.2f} | "
                         f"{row['angle_max']:.1f} |")
        lines.append("")
    output.with_suffix(".json").write_text(json.dumps(records, indent=1))
    lines += ["Reproduce: `bash bench/blender_mesh_write_profile.sh` (prepares the surfaces with the core, then runs "
              "every Blender it finds).", ""]
    output.with_suffix(".md").write_text("\n".join(lines))
    print("\n".join(lines))
    print(f"wrote {output.with_suffix('.md')} and {output.with_suffix('.json')}")


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--addon-path", default=str(ROOT / "build" / "addon"))
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--json", default="", help="write this run's results to this JSON file")
    parser.add_argument("--prepare", action="store_true", help="no Blender: reconstruct and cache the two surfaces")
    parser.add_argument("--report", nargs="+", metavar="JSON",
                        help="no Blender: merge runs' JSON files into bench/results/blender_mesh_write_profile.md")
    arguments = parser.parse_args(argv)
    if arguments.prepare:
        prepare(arguments.addon_path)
    elif arguments.report:
        write_report(arguments.report)
    else:
        run_blender(arguments)


if __name__ == "__main__":
    main()
