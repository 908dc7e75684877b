"""Speed and memory against the reference implementation (pysplashsurf, PyPI): both tools in one run, alternating,
several repetitions, medians and ratios (ours / theirs) of wall time and peak memory.

    bash bench/compare.sh                 # sets up, generates the frames, writes bench/results/compare.md (and .json)
    bash bench/compare.sh --quick         # the CI version (~1-2 min): build/bench/compare_quick.md, no timing targets

Cases: the shared frames and generated dam-break frames of 100 k, 1 M and 4 M particles (bench/generate_frame.py);
r = 0.025, l = 2, t = 0.6, c = 0.5 and 1.0; 1 and 2 threads; "reconstruction" (marching-cubes surface only) and
"full" (barnacle decimation, weights, smoothing: ours its default reach of 4.28 r, theirs 25 iterations; normals
with 10 smoothing iterations). Plus scaling
(time and memory per particle over 100 k - 4 M, thread speed-up) and a frame with a few far-flung droplets.

Every measurement runs in a fresh child process (this script with --child), which imports one tool, loads the
positions from a .npy cache (made once per input by the parent), records its resident memory (the baseline:
interpreter, numpy, the tool's module, the positions), times the one reconstruction call and reports its peak
resident memory (VmHWM). In --quick the run fails (exit 1) when a child fails or a mesh is empty or non-finite.
"""
import argparse
import datetime
import json
import os
import pathlib
import platform
import resource
import statistics
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data" / "splashsurf"
BENCH = ROOT / "build" / "bench"
CACHE = BENCH / "positions"
VENV_PYTHON = ROOT / "build" / "venv-bench" / "bin" / "python"
# The same seven frames as bench/compare_splashsurf.py.
FRAMES = [
    "bunny_frame_14_7705_particles.vtk",
    "dam_break_frame_9_6859_particles.bgeo",
    "double_dam_break_frame_01_4732_particles.vtk",
    "double_dam_break_frame_26_4732_particles.vtk",
    "hilbert_46843_particles.bgeo",
    "hilbert2_7954_particles.vtk",
    "pentagonal_hexecontahedron_32286_particles.bgeo",
]
QUICK_FRAME = "double_dam_break_frame_26_4732_particles.vtk"
SIZES = {"100k": 100_000, "1M": 1_000_000, "4M": 4_000_000}
RADIUS, SMOOTHING_LENGTH, ISO = 0.025, 2.0, 0.6
TOOLS = ("meniscus", "pysplashsurf")
MODES = ("reconstruction", "full")
# Targets (ours / theirs): full pipeline at 1 M and 4 M, reconstruction alone, every case; scaling and droplets.
FULL_TIME, FULL_MEMORY, RECONSTRUCTION_TIME, ANY_TIME = 0.5, 0.7, 1.0 / 1.2, 1.0
LARGE_INPUTS = ("generated_1M", "generated_4M")
SPEEDUP = 1.7            # 1 -> 2 threads on the 1 M frame
SCALING_SPREAD = 1.5     # "roughly constant per particle": largest / smallest value over 100 k - 4 M
FAR_FLUNG = 1.1          # "about what the frame without them costs": with / without
FAR_OFFSET = (100.0, 20.0, 50.0)
FAR_DROPLETS = 8


# ---------------------------------------------------------------------------------------------------------- child

def _status_bytes(field):
    """A VmRSS / VmHWM line of /proc/self/status, in bytes."""
    for line in pathlib.Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) * 1024
    return None


def child(args):
    """One measurement; prints one line `RESULT {json}` (also on failure, then with "error")."""
    import numpy as np
    out = {"ok": False}
    try:
        if args.tool == "meniscus":
            sys.path.insert(0, str(ROOT / "build" / "python"))
            import meniscus
            full = dict(decimate_barnacles=True, smoothing_iterations=25, normal_smoothing_iterations=10)  # + the default reach

            def run(positions):
                # Reconstruction alone: every post-processing stage off (the defaults run the whole pipeline).
                kwargs = full if args.mode == "full" else dict(decimate_barnacles=False, smoothing_iterations=0,
                                                               normals=False, normal_smoothing_iterations=0)
                mesh = meniscus.reconstruct(positions, particle_radius=RADIUS, smoothing_length=SMOOTHING_LENGTH,
                                            cube_size=args.cube, iso_threshold=ISO, threads=args.threads, **kwargs)
                return mesh, mesh.vertices, mesh.triangles, mesh.normals
        else:
            import pysplashsurf
            full = dict(decimate_barnacles=True, mesh_smoothing_iters=25, mesh_smoothing_weights=True,
                        compute_normals=True, normals_smoothing_iters=10)

            def run(positions):
                kwargs = full if args.mode == "full" else {}
                result = pysplashsurf.reconstruction_pipeline(
                    positions, particle_radius=RADIUS, smoothing_length=SMOOTHING_LENGTH, cube_size=args.cube,
                    iso_surface_threshold=ISO, multi_threading=True, **kwargs)
                mesh = result[0].mesh
                normals = result[0].point_attributes.get("normals") if args.mode == "full" else None
                return result, mesh.vertices, mesh.triangles, normals

        positions = np.load(args.positions)
        out["baseline_bytes"] = _status_bytes("VmRSS")
        start = time.perf_counter()
        keep, vertices, triangles, normals = run(positions)
        out["seconds"] = time.perf_counter() - start
        # Read the peak before anything else allocates. VmHWM is this process image's own high-water mark;
        # ru_maxrss (kept for reference) can carry the pre-exec peak of the process that started us.
        out["peak_bytes"] = _status_bytes("VmHWM")
        out["maxrss_bytes"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        out["particles"] = int(len(positions))
        out["vertices"], out["triangles"] = int(len(vertices)), int(len(triangles))
        problems = []
        if len(triangles) == 0:
            problems.append("empty mesh")
        if not np.isfinite(vertices).all():
            problems.append("non-finite vertices")
        if args.mode == "full" and (normals is None or not np.isfinite(np.asarray(normals)).all()):
            if args.tool == "meniscus":
                problems.append("missing or non-finite normals")
            else:  # the reference's own defect: its time still counts, the report says so
                out["warning"] = "non-finite normals"
        if problems:
            out["error"] = ", ".join(problems)
        else:
            out["ok"] = True
        del keep
    except BaseException as error:  # noqa: B902 - MemoryError included: reported, not raised
        out["error"] = f"{type(error).__name__}: {error}"
    print("RESULT " + json.dumps(out), flush=True)
    return 0 if out["ok"] else 1


# --------------------------------------------------------------------------------------------------------- parent

def machine():
    cpu = next((line.split(":", 1)[1].strip() for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines()
                if line.startswith("model name")), platform.processor() or "unknown CPU")
    mem = next((int(line.split()[1]) * 1024 for line in pathlib.Path("/proc/meminfo").read_text().splitlines()
                if line.startswith("MemTotal:")), 0)
    try:
        commit = subprocess.run(["git", "-C", str(ROOT), "describe", "--always", "--dirty"], capture_output=True,
                                text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    try:
        from importlib.metadata import version
        reference = version("pysplashsurf")
    except Exception:  # noqa: BLE001 - only for the report
        reference = "unknown"
    return {"nproc": os.cpu_count(), "cpu": cpu, "memory_gib": round(mem / 2**30, 1),
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "commit": commit, "pysplashsurf": reference, "python": platform.python_version(),
            "load_average_start": round(os.getloadavg()[0], 2)}


def warm_memory(fraction=0.75):
    """Touches most of the machine's memory once, in a throw-away process. On a virtual machine the first touch of a
    page the guest has never used costs several times a normal page fault (seen here: the first mesh adjacency of a
    fresh VM took 0.7 s, every later one 0.24 s), and whichever tool first reaches new memory would pay for it."""
    total = next(int(line.split()[1]) * 1024 for line in pathlib.Path("/proc/meminfo").read_text().splitlines()
                 if line.startswith("MemAvailable:"))
    chunks = int(fraction * total) >> 30
    print(f"touching {chunks} GiB of memory once (first-touch cost on virtual machines)", flush=True)
    subprocess.run([sys.executable, "-c", "import numpy as np\n"
                    f"held = [np.ones(1 << 30, dtype=np.uint8) for _ in range({chunks})]"], check=True)


def positions_cache(name, source):
    """The input's positions as float32 (N, 3) .npy, converted once (again only when the source is newer)."""
    import numpy as np
    CACHE.mkdir(parents=True, exist_ok=True)
    target = CACHE / f"{name}.npy"
    if not target.exists() or target.stat().st_mtime < source.stat().st_mtime:
        sys.path.insert(0, str(ROOT / "build" / "python"))
        import meniscus
        positions = np.ascontiguousarray(meniscus.read_particles(source).positions, dtype=np.float32)
        np.save(target, positions)
    return target


def far_flung_cache(name, base):
    """The base frame plus FAR_DROPLETS single particles far outside it: half beyond its upper corner by FAR_OFFSET
    (x, y, z), half beyond its lower corner, so the bounding box grows by about 2 * FAR_OFFSET in every direction."""
    import numpy as np
    target = CACHE / f"{name}.npy"
    if not target.exists() or target.stat().st_mtime < base.stat().st_mtime:
        positions = np.load(base)
        low, high = positions.min(axis=0), positions.max(axis=0)
        offset = np.array(FAR_OFFSET, dtype=np.float64)
        droplets = []
        for k in range(FAR_DROPLETS):
            step = (k // 2) * np.array([0.7, 1.3, 0.9])  # spread them apart (well over the kernel support)
            droplets.append(high + offset + step if k % 2 == 0 else low - offset - step)
        np.save(target, np.concatenate([positions, np.array(droplets, dtype=np.float32)]))
    return target


def generated_frame(label):
    path = BENCH / f"generated_{label}.vtk"
    if not path.exists():
        print(f"generating {path}", flush=True)
        subprocess.run([sys.executable, str(ROOT / "bench" / "generate_frame.py"), "--particles", str(SIZES[label]),
                        "--output", str(path)], check=True)
    return path


def run_child(args, tool, positions, cube, threads, mode):
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), RAYON_NUM_THREADS=str(threads))
    command = [str(args.python), str(pathlib.Path(__file__).resolve()), "--child", "--tool", tool, "--positions",
               str(positions), "--cube", str(cube), "--threads", str(threads), "--mode", mode]
    limit = int(args.memory_limit_gib * 2**30)

    def limit_memory():  # a runaway child fails on its own instead of taking the shared machine down
        if limit > 0:
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))

    try:
        process = subprocess.run(command, capture_output=True, text=True, env=env, timeout=args.timeout,
                                 preexec_fn=limit_memory)
    except subprocess.TimeoutExpired:
        return {"ok": False, "error": f"timed out after {args.timeout} s"}
    lines = [line for line in process.stdout.splitlines() if line.startswith("RESULT ")]
    result = json.loads(lines[-1][7:]) if lines else {"ok": False}
    if process.returncode != 0 and "error" not in result:
        how = f"killed by signal {-process.returncode}" if process.returncode < 0 else f"exit code {process.returncode}"
        tail = " | ".join(process.stderr.strip().splitlines()[-3:])
        result["error"] = how + (f": {tail}" if tail else "")
    return result


def summarise(runs):
    """Medians over the repetitions of one tool; None when any repetition failed."""
    if not runs or not all(r.get("ok") for r in runs):
        return None
    med = {key: statistics.median(r[key] for r in runs) for key in ("seconds", "peak_bytes", "baseline_bytes")}
    med["net_bytes"] = statistics.median(r["peak_bytes"] - r["baseline_bytes"] for r in runs)
    med["triangles"] = runs[0]["triangles"]
    return med


def ratio(case, key):
    ours, theirs = case["median"]["meniscus"], case["median"]["pysplashsurf"]
    if ours is None or theirs is None or not theirs[key]:
        return None
    return ours[key] / theirs[key]


def summarise_case(case):
    """Medians per tool and the ratios ours / theirs, from the case's runs."""
    case["median"] = {tool: summarise(case["runs"][tool]) for tool in TOOLS}
    case["time_ratio"], case["memory_ratio"] = ratio(case, "seconds"), ratio(case, "peak_bytes")
    case["net_memory_ratio"] = ratio(case, "net_bytes")


def measure(args, cases, key, input_name, positions, particles, cube, threads, mode, repetitions, output):
    """Runs one case: both tools per repetition, which one goes first alternating; stores it in `cases`."""
    case = {"input": input_name, "particles": particles, "cube": cube, "threads": threads, "mode": mode,
            "repetitions": repetitions, "runs": {tool: [] for tool in TOOLS}}
    for rep in range(repetitions):
        order = TOOLS if (len(cases) + rep) % 2 == 0 else TOOLS[::-1]
        for tool in order:
            result = run_child(args, tool, positions, cube, threads, mode)
            result["order"] = order.index(tool)
            case["runs"][tool].append(result)
            state = (f"{result['seconds']:.3f} s {result['peak_bytes'] / 2**20:.0f} MiB" if result.get("ok")
                     else "FAILED: " + result.get("error", "?"))
            print(f"[{time.strftime('%H:%M:%S')}] {input_name} c={cube} t={threads} {mode} rep {rep + 1}/{repetitions} "
                  f"{tool}: {state}", flush=True)
    summarise_case(case)
    cases[key] = case
    output.with_suffix(".json").write_text(json.dumps(output_json(args, cases), indent=1))  # partial results survive
    return case


def output_json(args, cases, extra=None):
    data = {"command": args.command, "machine": args.machine,
            "parameters": {"particle_radius": RADIUS, "smoothing_length": SMOOTHING_LENGTH, "iso_threshold": ISO,
                           "cubes": args.cubes, "threads": args.threads, "modes": args.modes},
            "cases": list(cases.values())}
    data.update(extra or {})
    return data


# ------------------------------------------------------------------------------------------------------- analysis

def row_checks(case):
    """The targets that apply to one row of the main table: (label, value, limit)."""
    checks = [("t", case["time_ratio"], ANY_TIME)]
    if case["mode"] == "reconstruction":
        checks.append(("t", case["time_ratio"], RECONSTRUCTION_TIME))
    elif case["input"] in LARGE_INPUTS:
        checks += [("t", case["time_ratio"], FULL_TIME), ("mem", case["memory_ratio"], FULL_MEMORY)]
    return checks


def verdict(checks):
    failed = [f"{label} ≤ {limit:.2f}" for label, value, limit in checks if value is None or value > limit]
    if any(value is None for _, value, _ in checks):
        return "not met (failed run)"
    return "met" if not failed else "not met: " + ", ".join(dict.fromkeys(failed))


def worst(items):
    """items: (value, where); the largest value (None counts as worst: a failed run)."""
    items = list(items)
    if not items:
        return None, "not measured"
    failed = [where for value, where in items if value is None]
    if failed:
        return None, "failed: " + failed[0]
    return max(items, key=lambda item: item[0])


def where(case):
    return f"{short(case['input'])}, c = {case['cube']}, {case['threads']} thr, {case['mode']}"


def short(name):
    return name.split("_particles")[0]


def fmt(value, spec=".3f"):
    return "failed" if value is None else format(value, spec)


def scaling_rows(args, cases, labels):
    threads = 2 if 2 in args.threads else max(args.threads)
    rows = []
    for cube in args.cubes:
        for mode in args.modes:
            for tool in TOOLS:
                per = []
                for label in labels:
                    case = cases.get(("generated_" + label, cube, threads, mode))
                    med = case["median"][tool] if case else None
                    per.append(None if med is None else (med["seconds"] / case["particles"] * 1e6,
                                                         med["net_bytes"] / case["particles"],
                                                         case["particles"], med["net_bytes"]))
                rows.append({"cube": cube, "mode": mode, "tool": tool, "threads": threads, "per_particle": per})
    for row in rows:
        values = row["per_particle"]
        ok = len(values) > 1 and all(v is not None for v in values)
        row["time_spread"] = max(v[0] for v in values) / min(v[0] for v in values) if ok else None
        row["memory_spread"] = max(v[1] for v in values) / max(1e-9, min(v[1] for v in values)) if ok else None
        # Memory = a fixed part (per-thread brick buffers, tables, allocator arenas) + a part per particle: bytes per
        # particle fall as the fixed part spreads. What must stay constant is the part per added particle, the
        # slope between consecutive sizes.
        slopes = [(b[3] - a[3]) / (b[2] - a[2]) for a, b in zip(values, values[1:])] if ok else []
        row["marginal_bytes"] = slopes
        row["marginal_spread"] = max(slopes) / max(1e-9, min(slopes)) if slopes and min(slopes) > 0 else None
    return rows


def speedup_rows(args, cases, labels):
    rows = []
    if not (1 in args.threads and 2 in args.threads):
        return rows
    for label in labels:
        for cube in args.cubes:
            for mode in args.modes:
                one, two = cases.get(("generated_" + label, cube, 1, mode)), cases.get(("generated_" + label, cube, 2, mode))
                row = {"input": "generated_" + label, "cube": cube, "mode": mode}
                for tool in TOOLS:
                    a = one["median"][tool] if one else None
                    b = two["median"][tool] if two else None
                    row[tool] = None if a is None or b is None else a["seconds"] / b["seconds"]
                rows.append(row)
    return rows


# -------------------------------------------------------------------------------------------------------- report

def report(args, cases, labels, far):
    m = args.machine
    main_cases = [c for key, c in cases.items() if key[0] != far.get("input")]
    scaling = scaling_rows(args, cases, labels)
    speedups = speedup_rows(args, cases, labels)
    # Summary: every target with its worst case.
    summary = []

    def target(text, value, place, limit, lower_is_better=True):
        if value is None:
            state = "not measured" if place == "not measured" else "**not met** (failed run)"
        else:
            good = value <= limit if lower_is_better else value >= limit
            state = "met" if good else "**not met**"
        shown = "–" if value is None else f"{value:.3f}"
        summary.append({"target": text, "worst": value, "where": place, "limit": limit, "state": state.strip("*")})
        return f"- {text}: worst {shown} ({place}) → {state}"

    large_full = [c for c in main_cases if c["mode"] == "full" and c["input"] in LARGE_INPUTS]
    recon = [c for c in main_cases if c["mode"] == "reconstruction"]
    lines_summary = [
        target("full pipeline at 1 M and 4 M: time ratio ≤ 0.5 (≥ 2× faster)", *worst((c["time_ratio"], where(c)) for c in large_full), FULL_TIME),
        target("full pipeline at 1 M and 4 M: peak memory ratio ≤ 0.7", *worst((c["memory_ratio"], where(c)) for c in large_full), FULL_MEMORY),
        target("reconstruction alone, every input: time ratio ≤ 0.833 (≥ 1.2× faster)", *worst((c["time_ratio"], where(c)) for c in recon), RECONSTRUCTION_TIME),
        target("no case slower than the reference: time ratio ≤ 1.0", *worst((c["time_ratio"], where(c)) for c in main_cases), ANY_TIME),
    ]
    ours_scaling = [r for r in scaling if r["tool"] == "meniscus"]
    if len(labels) > 1:
        lines_summary += [
            target(f"time per particle roughly constant over {labels[0]}-{labels[-1]} (ours, largest / smallest µs per particle ≤ {SCALING_SPREAD})",
                   *worst((r["time_spread"], f"c = {r['cube']}, {r['mode']}") for r in ours_scaling), SCALING_SPREAD),
            target(f"memory linear in the particles over {labels[0]}-{labels[-1]}: bytes per added particle roughly constant "
                   f"(ours, largest / smallest slope between consecutive sizes ≤ {SCALING_SPREAD}; bytes per particle fall "
                   "as the fixed part spreads, see the scaling table)",
                   *worst((r["marginal_spread"], f"c = {r['cube']}, {r['mode']}") for r in ours_scaling), SCALING_SPREAD),
        ]
    else:
        lines_summary.append(target("time and memory per particle roughly constant over 100 k - 4 M", None, "not measured", SCALING_SPREAD))
    one_m = [r for r in speedups if r["input"] == "generated_1M"]
    if one_m:
        value, place = min(((r["meniscus"], f"c = {r['cube']}, {r['mode']}") for r in one_m),
                           key=lambda item: -1 if item[0] is None else item[0])
        lines_summary.append(target(f"thread speed-up 1 → 2 threads on the 1 M frame ≥ {SPEEDUP} (ours; worst = smallest)",
                                    value, place if value is not None else "failed: " + place, SPEEDUP, lower_is_better=False))
    else:
        lines_summary.append(target(f"thread speed-up 1 → 2 threads on the 1 M frame ≥ {SPEEDUP}", None, "not measured", SPEEDUP, False))
    if far:
        ours = far["ratios"]["meniscus"]
        value = None if ours["time"] is None else max(ours["time"], ours["memory"])
        lines_summary.append(target(f"far-flung droplets cost about what the frame without them costs (ours, with / without ≤ {FAR_FLUNG}, time and memory)",
                                    value, far["input_label"] if value is not None else "failed: " + far["input_label"], FAR_FLUNG))

    reps = sorted({c["repetitions"] for c in cases.values()})
    lines = [
        "# Meniscus vs pysplashsurf: speed and peak memory",
        "",
        f"Machine: {m['nproc']} cores, {m['cpu']}, {m['memory_gib']} GiB; {m['date']}; meniscus {m['commit']}, "
        f"pysplashsurf {m['pysplashsurf']}, Python {m['python']}; 1-minute load average before the run "
        f"{m['load_average_start']} (about 0 on an idle machine).",
        f"Reproduce: `{args.command}`" + (" (the full run; `bash bench/compare.sh --quick` is the CI version)"
                                          if args.command == "bash bench/compare.sh" else "") + ".",
        "",
        f"r = {RADIUS}, l = {SMOOTHING_LENGTH}, t = {ISO}. Both tools run in one session, each measurement in a fresh "
        f"process, the two tools alternating which goes first; median of {'/'.join(map(str, reps))} "
        f"repetition{'' if reps == [1] else 's'}"
        + (" (the 4 M frame: fewer)" if len(reps) > 1 else "") + ". Time: the one reconstruction call "
        "(`meniscus.reconstruct` / `pysplashsurf.reconstruction_pipeline`) from numpy positions to numpy mesh. Peak "
        "memory: the process's peak resident set (VmHWM), which includes the interpreter, numpy, the tool's module and "
        "the positions (the baseline, about the same for both tools and listed in the JSON). "
        "Threads: `threads=` for ours; for pysplashsurf `multi_threading=True` with `RAYON_NUM_THREADS` set to the "
        "thread count (with one thread this is about 5 % faster than its `multi_threading=False`: we compare against its "
        "faster configuration); `OMP_NUM_THREADS` set too. pysplashsurf runs with its defaults otherwise (subdomain "
        "grid on with 64³ cubes per subdomain and auto-disable, SIMD on: its fastest documented configuration).",
        "",
        "**Reconstruction**: ours `normals=False`, no post-processing; theirs no options (it computes no normals by "
        "default). **Full**: barnacle decimation, smoothing weights, smoothing (ours: its default, the heat flow of reach "
        "4.28 r with its local return and per-component volume correction; theirs: 25 weighted iterations, which lose "
        "volume), normals with 10 smoothing iterations.",
        "",
        "## Targets (ratios ours / theirs)",
        "",
        *(["(Quick run: one repetition on a CI machine, so the timings are indicative only; it checks that both tools "
           "run and give non-empty, finite meshes, not the targets.)", ""] if args.quick else []),
        *lines_summary,
        "",
        "## All cases",
        "",
        f"Ratios are ours / theirs (below 1: we are faster or smaller). Targets per row: every row time ≤ {ANY_TIME:.2f}; "
        f"reconstruction time ≤ {RECONSTRUCTION_TIME:.3f}; full pipeline at 1 M and 4 M time ≤ {FULL_TIME:.2f} and "
        f"memory ≤ {FULL_MEMORY:.2f}.",
        "",
        "| input | particles | c | threads | mode | triangles (ours) | time ours (s) | time theirs (s) | time ratio | "
        "peak ours (MiB) | peak theirs (MiB) | memory ratio | target |",
        "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for c in main_cases:
        ours, theirs = c["median"]["meniscus"], c["median"]["pysplashsurf"]
        cells = [short(c["input"]), str(c["particles"]), str(c["cube"]), str(c["threads"]), c["mode"],
                 "failed" if ours is None else str(ours["triangles"]),
                 "failed" if ours is None else f"{ours['seconds']:.3f}",
                 "failed" if theirs is None else f"{theirs['seconds']:.3f}", fmt(c["time_ratio"]),
                 "failed" if ours is None else f"{ours['peak_bytes'] / 2**20:.0f}",
                 "failed" if theirs is None else f"{theirs['peak_bytes'] / 2**20:.0f}", fmt(c["memory_ratio"]),
                 verdict(row_checks(c))]
        lines.append("| " + " | ".join(cells) + " |")

    if scaling:
        threads = scaling[0]["threads"]
        lines += [
            "",
            f"## Scaling over the generated frames ({threads} thread{'s' if threads > 1 else ''})",
            "",
            "Microseconds per particle (median time / particles) and bytes per particle ((peak - baseline) / particles: "
            "the memory the reconstruction itself added); spread = largest / smallest over the sizes. Bytes per added "
            "particle = the slope of that memory between consecutive sizes (the fixed part drops out).",
            "",
            "| c | mode | tool | " + " | ".join(f"µs/particle {label}" for label in labels) + " | time spread | "
            + " | ".join(f"bytes/particle {label}" for label in labels) + " | memory spread | "
            + " | ".join(f"bytes per added particle {a}→{b}" for a, b in zip(labels, labels[1:])) + " |",
            "|---:|---|---|" + "---:|" * (2 * len(labels) + 2 + max(0, len(labels) - 1)),
        ]
        for r in scaling:
            t = ["failed" if v is None else f"{v[0]:.2f}" for v in r["per_particle"]]
            b = ["failed" if v is None else f"{v[1]:.0f}" for v in r["per_particle"]]
            spread = (lambda v: fmt(v, ".2f")) if len(labels) > 1 else (lambda v: "–")
            slopes = [f"{v:.0f}" for v in r.get("marginal_bytes") or []] or ["–"] * max(0, len(labels) - 1)
            lines.append(f"| {r['cube']} | {r['mode']} | {r['tool']} | " + " | ".join(t) + f" | {spread(r['time_spread'])} | "
                         + " | ".join(b) + f" | {spread(r['memory_spread'])} |" + "".join(f" {v} |" for v in slopes))
    if speedups:
        lines += ["", "## Thread speed-up (time with 1 thread / time with 2 threads)", "",
                  "| input | c | mode | ours | theirs |", "|---|---:|---|---:|---:|"]
        for r in speedups:
            lines.append(f"| {r['input']} | {r['cube']} | {r['mode']} | {fmt(r['meniscus'], '.2f')} | {fmt(r['pysplashsurf'], '.2f')} |")
    if far:
        lines += [
            "",
            f"## Far-flung droplets ({far['input_label']}, c = {far['cube']}, {far['threads']} "
            f"thread{'s' if far['threads'] > 1 else ''}, {far['mode']})",
            "",
            f"The frame plus {FAR_DROPLETS} single particles, half beyond its upper corner by (+{FAR_OFFSET[0]:g}, "
            f"+{FAR_OFFSET[1]:g}, +{FAR_OFFSET[2]:g}) and half beyond its lower corner by as much (bounding box "
            f"{far['box_growth']:.0f}× larger in volume). \"without\" is the main table's case of the same frame and settings.",
            "",
            "| tool | time without (s) | time with (s) | time with / without | peak without (MiB) | peak with (MiB) | "
            "memory with / without | triangles without, with |",
            "|---|---:|---:|---:|---:|---:|---:|---|",
        ]
        for tool in TOOLS:
            a, b, r = far["without"]["median"][tool], far["with"]["median"][tool], far["ratios"][tool]
            lines.append(f"| {tool} | {fmt(a and a['seconds'])} | {fmt(b and b['seconds'])} | {fmt(r['time'])} | "
                         f"{fmt(a and a['peak_bytes'] / 2**20, '.0f')} | {fmt(b and b['peak_bytes'] / 2**20, '.0f')} | "
                         f"{fmt(r['memory'])} | {a['triangles'] if a else 'failed'}, {b['triangles'] if b else 'failed'} |")
    blender = ROOT / "bench" / "results" / "blender_frame_change.md"
    if not args.quick and blender.exists():
        # The Blender side is measured by bench/blender_frame_change.sh (it needs Blender, not the reference tool);
        # its table is repeated here so that one page shows the whole frame.
        text = blender.read_text()
        table = [line for line in text.splitlines() if line.startswith("|")]
        split = next((i for i in range(1, len(table)) if table[i].startswith("| Blender")), len(table))
        lines += ["", "## Blender side: frame change to updated mesh (~1 M triangles)", "",
                  "From `bench/results/blender_frame_change.md` (`bash bench/blender_frame_change.sh`): `scene.frame_set` "
                  "timed end to end with the add-on's handler; *core* = `meniscus.reconstruct`, *Blender* = the rest "
                  "(mesh write, depsgraph).", "", *table[:split]]
    warned = sorted({(short(c["input"]), c["cube"], c["threads"], c["mode"], run["warning"]) for c in cases.values()
                     for run in c["runs"]["pysplashsurf"] if run.get("warning")})
    if warned:
        lines += ["", "**pysplashsurf's own defects** (its times still count): " + "; ".join(
            f"{name}, c = {cube}, {threads} thread{'s' if threads > 1 else ''}, {mode}: {warning}"
            for name, cube, threads, mode, warning in warned) + "."]
    failures = [(c, tool, run) for c in cases.values() for tool in TOOLS for run in c["runs"][tool] if not run.get("ok")]
    if failures:
        lines += ["", "## Failed runs", ""]
        lines += [f"- {where(c)}, {tool}: {run.get('error', '?')}" for c, tool, run in failures]
    return "\n".join(lines) + "\n", summary, scaling, speedups, failures


# ---------------------------------------------------------------------------------------------------------- main

def parse_list(text, kind):
    return [kind(item) for item in text.split(",") if item.strip()]


def report_from(args, path):
    """Writes the Markdown report again from a run's JSON (e.g. after a change to the report itself). A reference run
    that only failed for non-finite normals (its own defect) counts with a warning, as in newer runs."""
    data = json.loads(path.read_text())
    args.command, args.machine = data["command"], data["machine"]
    args.cubes, args.threads, args.modes = data["parameters"]["cubes"], data["parameters"]["threads"], data["parameters"]["modes"]
    cases = {}
    for case in data["cases"]:
        for run in case["runs"]["pysplashsurf"]:
            if not run.get("ok") and run.get("error") == "missing or non-finite normals" and "seconds" in run:
                run.update(ok=True, warning="non-finite normals")
                run.pop("error")
        summarise_case(case)
        cases[(case["input"], case["cube"], case["threads"], case["mode"])] = case
    labels = [label for label in SIZES if any(c["input"] == f"generated_{label}" for c in cases.values())]
    far = dict(data.get("far_flung") or {})
    if far:
        far["with"] = cases[(far["input"], far["cube"], far["threads"], far["mode"])]
        far["without"] = cases[(far["input"].replace("_far_droplets", ""), far["cube"], far["threads"], far["mode"])]
    markdown, summary, scaling, speedups, _ = report(args, cases, labels, far)
    extra = {k: v for k, v in data.items() if k not in ("command", "machine", "parameters", "cases")}
    extra.update(targets=summary, scaling=scaling, speedups=speedups)
    path.write_text(json.dumps(output_json(args, cases, extra), indent=1))
    path.with_suffix(".md").write_text(markdown)
    print(path.with_suffix(".md"))
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--report-from", type=pathlib.Path, help="write the report again from this run's JSON")
    parser.add_argument("--quick", action="store_true", help="CI version: generated 100k + one shared frame, c = 1.0, "
                        "threads 2 and 1, one repetition; writes build/bench/compare_quick.*; exit 1 on any failure")
    parser.add_argument("--sizes", default=None, help="generated sizes, e.g. 100k,1M (of 100k, 1M, 4M; 'none': no "
                        "generated frames); default all three (--quick: 100k)")
    parser.add_argument("--no-shared", action="store_true", help="skip the shared frames")
    parser.add_argument("--data", type=pathlib.Path, default=SHARED, help="folder of the shared frames")
    parser.add_argument("--cubes", default=None, help="cube sizes, default 0.5,1.0 (--quick: 1.0)")
    parser.add_argument("--threads", default=None, help="thread counts, default 1,2 (--quick: 2,1)")
    parser.add_argument("--modes", default="reconstruction,full")
    parser.add_argument("--repetitions", type=int, default=None, help="per case, default 3 (--quick: 1)")
    parser.add_argument("--repetitions-large", type=int, default=None, help="for the 4M frame, default 2")
    parser.add_argument("--no-far-flung", action="store_true", help="skip the far-flung droplets case")
    parser.add_argument("--no-warm-memory", action="store_true", help="do not touch the machine's memory before the run")
    parser.add_argument("--output", type=pathlib.Path, default=None,
                        help="output path without suffix (default bench/results/compare, --quick: build/bench/compare_quick)")
    parser.add_argument("--python", type=pathlib.Path, default=VENV_PYTHON if VENV_PYTHON.exists() else pathlib.Path(sys.executable),
                        help="interpreter for the children (needs numpy and pysplashsurf)")
    parser.add_argument("--timeout", type=float, default=3600.0, help="seconds per child")
    parser.add_argument("--memory-limit-gib", type=float, default=None,
                        help="address-space limit per child (default 75 %% of RAM; 0: none)")
    # Child mode (internal).
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--tool", choices=TOOLS, help=argparse.SUPPRESS)
    parser.add_argument("--positions", help=argparse.SUPPRESS)
    parser.add_argument("--cube", type=float, help=argparse.SUPPRESS)
    parser.add_argument("--mode", choices=MODES, help=argparse.SUPPRESS)
    argv = sys.argv[1:]
    if "--child" in argv:
        args = parser.parse_args(argv)
        args.threads = int(args.threads)
        return child(args)
    args = parser.parse_args(argv)
    if args.report_from:
        return report_from(args, args.report_from)

    args.command = "bash bench/compare.sh" + ("" if not argv else " " + " ".join(argv))
    labels = parse_list(args.sizes if args.sizes is not None else ("100k" if args.quick else "100k,1M,4M"), str)
    labels = [] if labels == ["none"] else labels
    for label in labels:
        if label not in SIZES:
            parser.error(f"--sizes: unknown size {label!r} (choose from {', '.join(SIZES)})")
    labels = sorted(labels, key=SIZES.get)
    args.cubes = parse_list(args.cubes or ("1.0" if args.quick else "0.5,1.0"), float)
    args.threads = parse_list(args.threads or ("2,1" if args.quick else "1,2"), int)
    args.modes = parse_list(args.modes, str)
    for mode in args.modes:
        if mode not in MODES:
            parser.error(f"--modes: unknown mode {mode!r}")
    repetitions = args.repetitions or (1 if args.quick else 3)
    repetitions_large = args.repetitions_large or (1 if args.quick else min(2, repetitions))
    output = args.output or (BENCH / "compare_quick" if args.quick else ROOT / "bench" / "results" / "compare")
    output.parent.mkdir(parents=True, exist_ok=True)
    if args.memory_limit_gib is None:
        total = next(int(line.split()[1]) * 1024 for line in pathlib.Path("/proc/meminfo").read_text().splitlines()
                     if line.startswith("MemTotal:"))
        args.memory_limit_gib = round(0.75 * total / 2**30, 1)
    args.machine = machine()
    if not args.quick and not args.no_warm_memory:
        warm_memory()
    if args.machine["load_average_start"] > 0.5:
        print(f"warning: load average {args.machine['load_average_start']}: the machine is not idle, timings will be "
              "noisy", file=sys.stderr, flush=True)

    import numpy as np
    inputs = []  # (name, cache path, particles, repetitions)
    frames = [] if args.no_shared else ([QUICK_FRAME] if args.quick else FRAMES)
    for frame in frames:
        name = pathlib.Path(frame).stem
        path = positions_cache(name, args.data / frame)
        inputs.append((name, path, repetitions))
    for label in labels:
        path = positions_cache(f"generated_{label}", generated_frame(label))
        inputs.append((f"generated_{label}", path, repetitions_large if label == "4M" else repetitions))
    counts = {name: int(np.load(path, mmap_mode="r").shape[0]) for name, path, _ in inputs}
    print(f"{len(inputs)} inputs x {len(args.cubes)} cubes x {len(args.threads)} thread counts x {len(args.modes)} modes; "
          f"children run {args.python}", flush=True)

    start = time.perf_counter()
    cases = {}
    for name, path, reps in inputs:
        for cube in args.cubes:
            for threads in args.threads:
                for mode in args.modes:
                    measure(args, cases, (name, cube, threads, mode), name, path, counts[name], cube, threads, mode, reps, output)

    far = {}
    if labels and not args.no_far_flung:
        # The 1 M frame when measured, else the largest generated one below it (the smallest otherwise).
        label = "1M" if "1M" in labels else max((l for l in labels if SIZES[l] <= SIZES["1M"]), key=SIZES.get, default=labels[0])
        cube = 0.5 if 0.5 in args.cubes else args.cubes[0]
        threads = 2 if 2 in args.threads else max(args.threads)
        mode = "full" if "full" in args.modes else args.modes[0]
        base_name = f"generated_{label}"
        base_path = next(path for name, path, _ in inputs if name == base_name)
        far_name = f"{base_name}_far_droplets"
        far_path = far_flung_cache(far_name, base_path)
        with_droplets = measure(args, cases, (far_name, cube, threads, mode), far_name, far_path,
                                int(np.load(far_path, mmap_mode="r").shape[0]), cube, threads, mode,
                                repetitions_large if label == "4M" else repetitions, output)
        without = cases[(base_name, cube, threads, mode)]
        p, q = np.load(base_path), np.load(far_path)
        growth = float(np.prod(q.max(0) - q.min(0)) / np.prod(p.max(0) - p.min(0)))
        ratios = {}
        for tool in TOOLS:
            a, b = without["median"][tool], with_droplets["median"][tool]
            ratios[tool] = {"time": None if a is None or b is None else b["seconds"] / a["seconds"],
                            "memory": None if a is None or b is None else b["peak_bytes"] / a["peak_bytes"]}
        far = {"input": far_name, "input_label": f"generated {label} + {FAR_DROPLETS} far droplets", "cube": cube,
               "threads": threads, "mode": mode, "box_growth": growth, "with": with_droplets, "without": without,
               "ratios": ratios}

    markdown, summary, scaling, speedups, failures = report(args, cases, labels, far)
    far_json = {k: v for k, v in far.items() if k not in ("with", "without")}
    output.with_suffix(".json").write_text(json.dumps(output_json(args, cases, {
        "targets": summary, "scaling": scaling, "speedups": speedups, "far_flung": far_json,
        "seconds_total": time.perf_counter() - start}), indent=1))
    output.with_suffix(".md").write_text(markdown)
    print(markdown)
    print(output.with_suffix(".md"), f"({time.perf_counter() - start:.0f} s)")
    if failures:
        print(f"{len(failures)} run(s) failed", file=sys.stderr)
        if args.quick:
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
