"""Cost of the smoothing at 1 M particles (bench/generate_frame.py), every variant in one run, alternating, in fresh
processes, best of --repetitions: the pipeline's stage seconds (smoothing = heat flow + local return + final
correction; before issue 12: smoothing + volume restoration), the heat stage's own split, and the stage total.

    python3 bench/generate_frame.py --particles 1000000 --output build/bench/generated_1M.vtk
    python3 bench/smoothing_cost.py --frame build/bench/generated_1M.vtk --cube 0.5 --threads 2
Writes bench/results/smoothing/cost_1M_c{cube}.json. On a shared machine compare ratios within one run.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
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


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frame", default=str(ROOT / "build" / "bench" / "generated_1M.vtk"))
    parser.add_argument("--cube", type=float, default=0.5)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repetitions", type=int, default=2)
    parser.add_argument("--variants", default=None, help="comma-separated indices into the variant list")
    parser.add_argument("--child", default=None)
    args = parser.parse_args()
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
    output = ROOT / "bench" / "results" / "smoothing" / f"cost_1M_c{args.cube}.json"
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps(dict(cube=args.cube, threads=args.threads, runs=runs, best=summary), indent=1))
    for n, s in summary.items():
        print(f"{n}: smoothing {s['smoothing']:.2f} s ({100 * s['share']:.0f} % of {s['stage_sum']:.2f} s), "
              f"x{s['smoothing_vs_before']:.2f} of before; pipeline x{s['pipeline_vs_before']:.2f}")


if __name__ == "__main__":
    main()
