"""Blender side of a frame change: from `scene.frame_set(f)` to the updated ~1 M-triangle surface, with the core's
and Blender's shares.

    bash bench/blender_frame_change.sh        # every tested Blender, writes bench/results/blender_frame_change.md
    (it installs the add-on from dist/ into a fresh user folder per Blender, then runs this script there)
    /usr/bin/python3 bench/blender_frame_change.py --report build/bench/blender_frame_change_*.json

Input (prepared once, cached in build/bench/blender_frame_change/): FRAMES legacy VTK files (binary) made from the
splashsurf set pentagonal_hexecontahedron_32286_particles.bgeo, each with its own small Gaussian jitter of the
positions (so every frame is a different reconstruction) and a synthetic `velocity` vector attribute (carried to
the mesh for motion blur, as with simulation data). With the add-on's default pipeline (radius 0.025, smoothing
length 2, iso 0.6, barnacle decimation, 25 weighted smoothing iterations, volume restoration, normals with 10
smoothing iterations) and cube size 0.57 this gives about 990 000 triangles per frame.

In Blender: the add-on is registered, the sequence added with its own operator (`meniscus.add_sequence`), the
viewport and render cube sizes set to 0.57 and the pipeline parameters set explicitly to the defaults. Then each
measured frame change is `scene.frame_set(f)` timed end to end: frame_change_post runs the add-on's handler
(read the file, reconstruct, write the mesh) and frame_set then re-evaluates the depsgraph with the new mesh. The
parts are timed inside the same call by wrapping, in this process only, the functions the handler calls:
  read     meniscus.api.read_particles            (file -> positions and attributes)
  core     meniscus.api.reconstruct               (the C++ core incl. its pybind11 call; core_stages = the
                                                   core's own per-stage seconds, mesh.stats)
  write    <add-on>.blender.mesh_update.write_surface (arrays -> Blender mesh: geometry, attributes, normals)
  handler  <add-on>.blender.update.update_scene (the whole frame_change_post work)
  Blender  = total - core - read = write + add-on glue + depsgraph evaluation and the rest of frame_set
Every frame change goes to another file, so each one reconstructs. The first frame change after the parameters are
set is a warm-up (the mesh grows from the add operator's coarse preview to 1 M triangles, attributes are created)
and is reported separately; the table gives the median of the following changes. Runs with the add-on's default
`use_custom_normals` (on) and with it off.
"""
import json
import os
import pathlib
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
PARTICLES = ROOT.parent / "shared" / "data" / "splashsurf" / "pentagonal_hexecontahedron_32286_particles.bgeo"  # ../shared beside the clone
FRAME_DIR = ROOT / "build" / "bench" / "blender_frame_change"
FRAME_NAME = "pentagonal_jitter_{:04d}.vtk"
FRAMES = 4
RADIUS = 0.025
CUBE_SIZE = 0.57          # x radius: ~990 000 triangles with the full pipeline on this set (0.55: 1.06 M)
JITTER = 0.04             # x radius: standard deviation of the per-frame position jitter
MEASURED = 5              # frame changes measured per setting, after one warm-up change
RESULTS = ROOT / "bench" / "results" / "blender_frame_change"


# ---- input frames (no bpy needed) ---------------------------------------------------------------------------------

def write_vtk(path, positions, velocity):
    """bench/generate_frame.write_vtk with a `velocity` attribute, written next to its final name, then renamed."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
    from generate_frame import write_vtk as write_frame

    temporary = path.with_name(path.name + ".partial")
    write_frame(temporary, positions, velocity)
    os.replace(temporary, path)


def frame_paths():
    return [FRAME_DIR / FRAME_NAME.format(frame) for frame in range(1, FRAMES + 1)]


def prepare_frames():
    """Writes the jittered frames once; returns their paths."""
    paths = frame_paths()
    if all(path.is_file() for path in paths):
        return paths
    import numpy as np
    import meniscus

    base = meniscus.read_particles(str(PARTICLES)).positions.astype(np.float64)
    FRAME_DIR.mkdir(parents=True, exist_ok=True)
    for frame, path in enumerate(paths, start=1):
        rng = np.random.default_rng(1000 + frame)
        offset = rng.normal(0.0, JITTER * RADIUS, base.shape)
        velocity = offset * 24.0 + rng.normal(0.0, 0.1, base.shape)  # synthetic, only its size and type matter
        write_vtk(path, (base + offset).astype(np.float32), velocity.astype(np.float32))
        print(f"wrote {path}")
    return paths


# ---- the Blender run ----------------------------------------------------------------------------------------------

class Timers:
    """Wraps functions the frame handler calls (module attributes, looked up at call time) and sums their seconds."""

    def __init__(self):
        self.seconds = {}
        self.core_stages = {}
        self.triangles = 0

    def wrap(self, module, name, key):
        original = getattr(module, name)

        def timed(*args, **kwargs):
            started = time.perf_counter()
            try:
                result = original(*args, **kwargs)
            finally:
                self.seconds[key] = self.seconds.get(key, 0.0) + time.perf_counter() - started
            if key == "core":
                for stage, value in result.stats.get("seconds", {}).items():
                    self.core_stages[stage] = self.core_stages.get(stage, 0.0) + value
                self.triangles = len(result.triangles)
            return result

        setattr(module, name, timed)

    def reset(self):
        self.seconds, self.core_stages, self.triangles = {}, {}, 0


def measure_frame_change(bpy, scene, obj, timers, frame):
    timers.reset()
    started = time.perf_counter()
    scene.frame_set(frame)
    total = time.perf_counter() - started
    settings = obj.meniscus
    if settings.status_is_error:
        raise RuntimeError(f"frame {frame}: {settings.status}")
    seconds = dict(timers.seconds)
    for key in ("read", "core", "write", "handler"):
        if key not in seconds:
            raise RuntimeError(f"frame {frame}: no '{key}' time, the surface was not rebuilt ({settings.status!r})")
    record = {
        "frame": frame,
        "total": total,
        "read": seconds["read"],
        "core": seconds["core"],
        "write": seconds["write"],
        "handoff": seconds.get("handoff", 0.0),
        "handler": seconds["handler"],
        "glue": seconds["handler"] - seconds["read"] - seconds["core"] - seconds["write"],
        "depsgraph_and_rest": total - seconds["handler"],
        "blender": total - seconds["core"] - seconds["read"],
        "core_stages_sum": sum(timers.core_stages.values()),
        "core_stages": dict(timers.core_stages),
        "triangles": len(obj.data.polygons),
        "vertices": len(obj.data.vertices),
        "core_triangles": timers.triangles,
        "status": settings.status.replace("\n", " | "),
        "load_average_1min": os.getloadavg()[0],
    }
    print(f"  frame {frame}: total {total:.3f} s = read {record['read']:.3f} + core {record['core']:.3f} + "
          f"write {record['write']:.3f} + glue {record['glue']:.3f} (hand-off {record['handoff']:.3f}) + depsgraph/rest "
          f"{record['depsgraph_and_rest']:.3f}; {record['triangles']} triangles; beyond the core "
          f"{(total - record['core'] - record['read']) / max(record['triangles'], 1) * 1e6:.3f} s per M triangles")
    sys.stdout.flush()
    return record


SUMMARY_KEYS = ("total", "core", "read", "blender", "write", "glue", "depsgraph_and_rest", "core_stages_sum")


def summarize(runs):
    warm_up, measured = runs[0], runs[1:]
    medians = {key: statistics.median(run[key] for run in measured) for key in SUMMARY_KEYS}
    medians["blender_share"] = statistics.median(run["blender"] / run["total"] for run in measured)
    # Minimum per column too: on a machine shared with other jobs it is the least disturbed value.
    minima = {key: min(run[key] for run in measured) for key in SUMMARY_KEYS}
    return {"warm_up": warm_up, "frames": measured, "median": medians, "min": minima,
            "triangles": int(statistics.median(run["triangles"] for run in measured))}


def run_blender(arguments):
    import bpy

    as_module = not bpy.app.binary_path
    # The add-on as a user has it: bench/blender_frame_change.sh installed the zip into a fresh user folder (the
    # test suite's install step); here it is enabled as the Preferences checkbox does.
    sys.path.insert(0, str(ROOT / "tests" / "blender"))
    import _support

    addon = _support.enable_addon()
    api = addon.api
    update, mesh_update = _support.addon_modules(addon, "blender.update", "blender.mesh_update")
    paths = prepare_frames()

    timers = Timers()
    timers.wrap(api, "read_particles", "read")
    timers.wrap(api, "reconstruct", "core")
    timers.wrap(mesh_update, "write_surface", "write")
    if hasattr(mesh_update, "_mesh_arrays"):  # the core's arrays in Blender's layout (part of glue); older add-ons
        timers.wrap(mesh_update, "_mesh_arrays", "handoff")  # made them in numpy
    # Frame changes that were not prefetched: nothing is built ahead, and each frame's kept result is dropped before
    # the change (below), so every change reads, reconstructs, hands off and writes on Blender's thread.
    update.PREFETCH_AHEAD = 0
    timers.wrap(update, "update_scene", "handler")

    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    scene = bpy.context.scene
    scene.frame_set(1)
    result = bpy.ops.meniscus.add_sequence(filepath=str(paths[0]), particle_radius=RADIUS)
    assert result == {"FINISHED"}, result
    obj = next(o for o in bpy.data.objects if update.is_surface(o))
    settings = obj.meniscus
    assert (settings.frame_start, settings.frame_end) == (1, FRAMES), (settings.frame_start, settings.frame_end)

    # Parameters set with is_surface off, so that each field does not trigger a rebuild of its own.
    settings.is_surface = False
    settings.particle_radius = RADIUS
    settings.cube_size = settings.render_cube_size = CUBE_SIZE
    settings.smoothing_length, settings.iso_threshold = 2.0, 0.6
    settings.decimate_barnacles, settings.mesh_cleanup = True, False
    settings.smoothing_iterations, settings.smoothing_strength = 25, 1.0
    settings.smoothing_weights, settings.weights_normalization_auto, settings.volume_restoration = True, True, True
    settings.normal_smoothing_iterations, settings.sph_normals = 10, False
    settings.threads_auto = True
    settings.is_surface = True
    parameters = update.reconstruction_arguments(settings, for_render=False)

    load_before = os.getloadavg()
    record = {"blender": bpy.app.version_string, "as_module": as_module, "cube_size": CUBE_SIZE, "radius": RADIUS,
              "frames_on_disk": FRAMES, "jitter_x_radius": JITTER, "particles": str(PARTICLES),
              "parameters": {k: v for k, v in parameters.items() if k != "normals"}, "settings": {}}
    print(f"Blender {bpy.app.version_string}: {FRAMES} frames from {paths[0].parent}, cube size {CUBE_SIZE} x r")
    frame = 1
    for use_custom_normals in (True, False):
        settings.is_surface = False
        settings.use_custom_normals = use_custom_normals
        settings.is_surface = True
        print(f" custom normals {'on' if use_custom_normals else 'off'}")
        runs = []
        for _ in range(MEASURED + 1):
            frame = frame % FRAMES + 1  # always another file: every change reconstructs
            update.forget_frames(obj)
            runs.append(measure_frame_change(bpy, scene, obj, timers, frame))
        summary = summarize(runs)
        record["settings"]["custom_normals_on" if use_custom_normals else "custom_normals_off"] = summary
        m = summary["median"]
        print(f"  median of {MEASURED}: total {m['total']:.3f} s, core {m['core']:.3f}, read {m['read']:.3f}, "
              f"Blender {m['blender']:.3f} ({100 * m['blender_share']:.0f} %); warm-up {summary['warm_up']['total']:.3f}")
    record["load_average_before"] = load_before
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

def _load(summary):
    """Median 1-minute load average over the measured frame changes (2 cores: above ~2 another job competed)."""
    loads = [run["load_average_1min"] for run in summary["frames"] if "load_average_1min" in run]
    return f"{statistics.median(loads):.1f}" if loads else "–"


def write_report(json_paths, output=RESULTS):
    records = [json.loads(pathlib.Path(path).read_text()) for path in json_paths]
    rows = []
    for record in records:
        for key, label in (("custom_normals_on", "on (default)"), ("custom_normals_off", "off")):
            summary = record["settings"][key]
            summary.setdefault("min", {k: min(run[k] for run in summary["frames"]) for k in SUMMARY_KEYS})
            rows.append((record, label, summary))

    lines = [
        "# Blender side: frame change to updated mesh (~1 M triangles)", "",
        f"`scene.frame_set(f)` timed end to end (the add-on's frame_change_post handler reads the particle file, "
        f"reconstructs and writes the mesh; frame_set then re-evaluates the depsgraph), **median of "
        f"{len(records[0]['settings']['custom_normals_on']['frames'])} frame changes** after one warm-up change, "
        f"each to another file. Input: {FRAMES} jittered copies of `pentagonal_hexecontahedron_32286_particles.bgeo` "
        f"with a `velocity` attribute (legacy VTK, cached in `build/bench/blender_frame_change/`), the add-on's "
        f"default pipeline (r = {RADIUS}, l = 2, t = 0.6, barnacle decimation, the smoothing of a "
        f"4.28 r reach with its volume correction, 10 normal-smoothing iterations, all threads) at viewport = render cube size "
        f"**{CUBE_SIZE}**. 2 cores (load averages in the JSON; the run itself keeps both busy).", "",
        "*core* = `meniscus.api.reconstruct` (the C++ core and its pybind11 call), *read* = "
        "`meniscus.api.read_particles`, both timed inside the frame change; *Blender* = total − core − read "
        "(mesh write + the add-on's glue + depsgraph evaluation and the rest of frame_set). Each column is a median "
        "on its own, so the columns need not add up exactly.", "",
        "| Blender | custom normals | triangles | frame change total (s) | core (s) | read (s) | Blender (s) | "
        "Blender share |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for record, label, summary in rows:
        m = summary["median"]
        lines.append(f"| {record['blender']} | {label} | {summary['triangles']:,} | {m['total']:.3f} | "
                     f"{m['core']:.3f} | {m['read']:.3f} | {m['blender']:.3f} | {100 * m['blender_share']:.0f} % |")
    lines += [
        "", "Blender's share split up (medians, s); *first change* = the warm-up change's total (the mesh grows from "
        "the add operator's coarse preview, attributes are created), not in the medians; *min* = the least disturbed "
        "of the measured changes:", "",
        "| Blender | custom normals | mesh write (`write_surface`) | add-on glue | depsgraph + rest of frame_set | "
        "core's own stage sum | first change total | min total | min core | load average |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for record, label, summary in rows:
        m = summary["median"]
        lines.append(f"| {record['blender']} | {label} | {m['write']:.3f} | {m['glue']:.3f} | "
                     f"{m['depsgraph_and_rest']:.3f} | {m['core_stages_sum']:.3f} | {summary['warm_up']['total']:.3f} | "
                     f"{summary['min']['total']:.3f} | {summary['min']['core']:.3f} | {_load(summary)} |")
    lines += [
        "", "Reproduce: `bash bench/blender_frame_change.sh` (or the three commands in the header of "
        "`bench/blender_frame_change.py`); other bpy versions for Python 3.11 through `BPY_PYTHONS`, e.g. "
        "`BPY_PYTHONS=\"/tmp/venvs/bpy-4.2/bin/python /tmp/venvs/bpy-5.0/bin/python\" bash "
        "bench/blender_frame_change.sh`.", "",
    ]
    output.with_suffix(".md").write_text("\n".join(lines))
    output.with_suffix(".json").write_text(json.dumps(records, indent=1))
    print("\n".join(lines))
    print(f"wrote {output.with_suffix('.md')} and {output.with_suffix('.json')}")


def main():
    import argparse

    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", default="", help="write this run's results to this JSON file")
    parser.add_argument("--report", nargs="+", metavar="JSON",
                        help="no Blender: merge these runs' JSON files into bench/results/blender_frame_change.md/.json")
    arguments = parser.parse_args(argv)
    if arguments.report:
        write_report(arguments.report)
    else:
        run_blender(arguments)


if __name__ == "__main__":
    main()
