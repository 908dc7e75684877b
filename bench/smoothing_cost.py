"""Cost of the smoothing at 1 M particles (bench/generate_frame.py), every variant in one run, alternating, in fresh
processes, best of --repetitions: the pipeline's stage seconds (smoothing = heat flow + local return + final
correction; before issue 12: smoothing + volume restoration), the heat stage's own split, and the stage total.

    python3 bench/generate_frame.py --particles 1000000 --output build/bench/generated_1M.vtk
    python3 bench/smoothing_cost.py --frame build/bench/generated_1M.vtk --cube 0.5 --threads 2
Writes bench/results/smoothing/cost_1M_c{cube}.json. On a shared machine compare ratios within one run.

    python3 bench/smoothing_cost.py --shared [--frames a.vtk,b.bgeo] [--cubes 0.25,0.5,1.0] [--name NAME]
The issue's target on the shared frames (../shared/data/splashsurf): per frame and cube size the default smoothing
(smoothing + its counts) against the paper's 25 iterations with volume restoration (smoothing_reach 0), both
alternating in one process, best of --repetitions; writes bench/results/smoothing/cost_shared[_NAME].json.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results" / "smoothing"
VARIANTS = {
    "25 explicit iterations + restoration (smoothing_reach 0)": dict(smoothing_reach=0.0),
    "reach 4.28 r (2 parts)": dict(smoothing_reach=4.28),
    "reach 2.68 r (1 part)": dict(smoothing_reach=2.68),
    "no smoothing": dict(smoothing_iterations=0),
}


def child(frame, cube, threads, variant):
    sys.path.insert(0, str(ROOT / "build" / "python"))
    import meniscus
    positions = meniscus.read_particles(frame).positions
    start = time.perf_counter()
    mesh = meniscus.reconstruct(positions, 0.025, cube_size=cube, threads=threads, **VARIANTS[variant])
    total = time.perf_counter() - start
    stages = mesh.stats["seconds"]
    print(json.dumps(dict(variant=variant, total=total, stages=stages, stage_sum=sum(stages.values()),
                          smoothing=stages.get("smoothing", 0.0) + stages.get("volume restoration", 0.0),
                          normals=stages.get("normals", 0.0), vertices=len(mesh.vertices),
                          applications=mesh.stats["counts"].get("smoothing_applications"))))


SHARED = ROOT.parent / "shared" / "data" / "splashsurf"
PAPER = dict(smoothing_reach=0.0)


def shared(args):
    """Default vs the paper's iterations on the shared frames, alternating within one process (same load)."""
    sys.path.insert(0, str(ROOT / "build" / "python"))
    import meniscus
    frames = args.frames.split(",") if args.frames else sorted(p.name for p in SHARED.glob("*") if p.suffix in (".vtk", ".bgeo"))
    cubes = [float(c) for c in args.cubes.split(",")]
    rows = []
    for frame in frames:
        positions = meniscus.read_particles(str(SHARED / frame)).positions
        for cube in cubes:
            best = {}
            for _ in range(args.repetitions):
                for name, kwargs in (("default", {}), ("paper", PAPER)):
                    mesh = meniscus.reconstruct(positions, 0.025, cube_size=cube, threads=args.threads, **kwargs)
                    stages, counts = mesh.stats["seconds"], mesh.stats["counts"]
                    seconds = stages.get("smoothing", 0.0) + stages.get("volume restoration", 0.0)
                    if name not in best or seconds < best[name]["smoothing"]:
                        best[name] = dict(smoothing=seconds, stage_sum=sum(stages.values()),
                                          **{k: v for k, v in counts.items() if k.startswith("smoothing")})
            row = dict(frame=frame, cube=cube, particles=len(positions), default=best["default"], paper=best["paper"],
                       ratio=best["default"]["smoothing"] / best["paper"]["smoothing"])
            rows.append(row)
            d = best["default"]
            print(f"{frame} c={cube}: default {d['smoothing']:.3f} s (flow {d.get('smoothing_flow_seconds', 0):.3f}, return "
                  f"{d.get('smoothing_return_seconds', 0):.3f}, correction {d.get('smoothing_correction_seconds', 0):.3f}; "
                  f"{d.get('smoothing_parts', 0):.0f} parts, {d.get('smoothing_applications', 0):.0f} applications) vs paper "
                  f"{best['paper']['smoothing']:.3f} s: x{row['ratio']:.2f}", flush=True)
    for frame in frames:  # c = 1.0 against c = 0.5 of the same frame (the "at most half")
        by_cube = {r["cube"]: r["default"]["smoothing"] for r in rows if r["frame"] == frame}
        if 0.5 in by_cube and 1.0 in by_cube:
            print(f"{frame}: default c = 1.0 / c = 0.5 = {by_cube[1.0] / by_cube[0.5]:.2f}")
    output = RESULTS / f"cost_shared{'_' + args.name if args.name else ''}.json"
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps(dict(threads=args.threads, repetitions=args.repetitions, rows=rows), indent=1))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frame", default=str(ROOT / "build" / "bench" / "generated_1M.vtk"))
    parser.add_argument("--cube", type=float, default=0.5)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repetitions", type=int, default=2)
    parser.add_argument("--variants", default=None, help="comma-separated indices into the variant list")
    parser.add_argument("--child", default=None)
    parser.add_argument("--shared", action="store_true", help="the shared frames, default vs the paper's iterations")
    parser.add_argument("--frames", default=None, help="with --shared: comma-separated file names")
    parser.add_argument("--cubes", default="0.25,0.5,1.0", help="with --shared")
    parser.add_argument("--name", default="", help="with --shared: output file name part")
    args = parser.parse_args()
    if args.shared:
        shared(args)
        return
    if args.child:
        child(args.frame, args.cube, args.threads, args.child)
        return
    names = list(VARIANTS)
    if args.variants:
        names = [names[int(i)] for i in args.variants.split(",")]
    runs = {n: [] for n in names}
    for _ in range(args.repetitions):
        for name in names:
            out = subprocess.run([sys.executable, __file__, "--frame", args.frame, "--cube", str(args.cube), "--threads",
                                  str(args.threads), "--child", name], check=True, capture_output=True, text=True).stdout
            runs[name].append(json.loads(out.strip().splitlines()[-1]))
            print(out.strip(), flush=True)
    best = {n: min(r, key=lambda x: x["stage_sum"]) for n, r in runs.items()}
    reference = best.get(names[0])
    summary = {n: dict(smoothing=b["smoothing"], stage_sum=b["stage_sum"], share=b["smoothing"] / b["stage_sum"],
                       smoothing_vs_before=b["smoothing"] / reference["smoothing"] if reference and reference["smoothing"] else None,
                       pipeline_vs_before=b["stage_sum"] / reference["stage_sum"] if reference else None,
                       applications=b["applications"], vertices=b["vertices"]) for n, b in best.items()}
    output = RESULTS / f"cost_1M_c{args.cube}.json"
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps(dict(cube=args.cube, threads=args.threads, runs=runs, best=summary), indent=1))
    for n, s in summary.items():
        print(f"{n}: smoothing {s['smoothing']:.2f} s ({100 * s['share']:.0f} % of {s['stage_sum']:.2f} s), "
              f"x{s['smoothing_vs_before']:.2f} of before; pipeline x{s['pipeline_vs_before']:.2f}")


if __name__ == "__main__":
    main()
