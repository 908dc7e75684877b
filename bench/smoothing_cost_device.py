"""The smoothing's cost targets of issue 21 with the CLI only, in plain Python (no numpy): on a many-core machine with
several core pairs at once; on a 2-core one with --pairs 0,1 --busy-cores "" and then the busy check alone.

Each worker is pinned to its own pair of cores (taskset) and runs --threads 2, so several frames are measured at once
without sharing cores; per (frame, cube size) the variants alternate on the same pair, best of --repetitions:
  after   the build under test (build/bin/meniscus), default smoothing (the reach)
  paper   the same build with --mesh-smoothing-reach 0 (the paper's 25 iterations with volume restoration)
  before  an older build given by --before (default smoothing), if there is one
Then the busy check: c = 1.0 against c = 0.5 of one frame, alone and with two CLI loops beside it on the same pair
(--busy-all: of every frame, each on a worker's pair once the cost jobs are done).

    python3 bench/smoothing_cost_device.py --frames build/bench-device/frames --before build/bench-device/meniscus_before \
        --output $OUT/smoothing_cost_device.json
Smoothing seconds: the "smoothing" stage (the reach: flow, returns, final correction) or "smoothing" + "volume
restoration" (the paper's iterations).
"""
import argparse
import json
import os
import pathlib
import queue
import subprocess
import tempfile
import threading
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]


def run(cli, frame, cube, cores, extra=(), radius=0.025):
    with tempfile.TemporaryDirectory() as tmp:
        stats = pathlib.Path(tmp) / "stats.json"
        command = ["taskset", "-c", cores, str(cli), "reconstruct", str(frame), "-o", str(pathlib.Path(tmp) / "out.ply"), "-r", str(radius),
                   "-c", str(cube), "--threads", "2", "--stats", str(stats), "-q", *extra]
        subprocess.run(command, check=True, capture_output=True)
        record = json.loads(stats.read_text())["frames"][0]
    seconds, counts = record["seconds"], record.get("counts", {})
    return dict(smoothing=seconds.get("smoothing", 0.0) + seconds.get("volume restoration", 0.0), total=seconds.get("total"),
                **{k: v for k, v in counts.items() if k.startswith("smoothing")})


def measure(job, cores, args, variants):
    frame, cube = job
    best = {}
    for _ in range(args.repetitions):
        for name, (cli, extra) in variants.items():
            r = run(cli, frame, cube, cores, extra)
            if name not in best or r["smoothing"] < best[name]["smoothing"]:
                best[name] = r
    row = dict(frame=frame.name, cube=cube, cores=cores, **{name: best[name] for name in best})
    row["after_vs_paper"] = best["after"]["smoothing"] / best["paper"]["smoothing"]
    if "before" in best:
        row["before_vs_paper"] = best["before"]["smoothing"] / best["paper"]["smoothing"]
    return row


def busy(args, cli, frame, cores, deadline):
    """c = 1.0 vs c = 0.5 smoothing of one frame, alone and beside two CLI loops on the same cores."""
    result = {}
    for mode in ("alone", "two busy"):
        loops = []
        if mode == "two busy":
            for _ in range(2):
                script = f"while true; do taskset -c {cores} {cli} reconstruct {frame} -o /tmp/busy_$$.ply -r 0.025 -c 0.5 --threads 2 -q; done"
                loops.append(subprocess.Popen(["bash", "-c", script], start_new_session=True))
        try:
            best = {}
            for _ in range(args.repetitions):
                for cube in (0.5, 1.0):
                    if time.time() > deadline:
                        break
                    r = run(cli, frame, cube, cores)
                    if cube not in best or r["smoothing"] < best[cube]["smoothing"]:
                        best[cube] = r
            result[mode] = {str(c): b["smoothing"] for c, b in best.items()}
            if 0.5 in best and 1.0 in best:
                result[mode]["c1_vs_c05"] = best[1.0]["smoothing"] / best[0.5]["smoothing"]
        finally:
            for p in loops:
                os.killpg(p.pid, 9)
                p.wait()
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cli", default=str(ROOT / "build" / "bin" / "meniscus"))
    parser.add_argument("--before", default="")
    parser.add_argument("--frames", default=str(ROOT.parent / "shared" / "data" / "splashsurf"))
    parser.add_argument("--large", default="", help="a large frame (e.g. the generated 1 M) measured at c = 0.5")
    parser.add_argument("--cubes", default="0.25,0.5,1.0")
    parser.add_argument("--repetitions", type=int, default=2)
    parser.add_argument("--pairs", default="0,1;2,3;4,5;6,7;8,9;10,11", help="';'-separated core pairs, one worker each")
    parser.add_argument("--busy-cores", default="14,15")
    parser.add_argument("--busy-all", action="store_true", help="the busy check of every frame, on the workers' pairs")
    parser.add_argument("--budget", type=float, default=300.0, help="seconds; jobs not started by then are skipped")
    parser.add_argument("--output", default="smoothing_cost_device.json")
    args = parser.parse_args()
    deadline = time.time() + args.budget
    variants = {"after": (args.cli, ()), "paper": (args.cli, ("--mesh-smoothing-reach", "0"))}
    if args.before and pathlib.Path(args.before).exists():
        variants["before"] = (args.before, ())
    frames = sorted(p for p in pathlib.Path(args.frames).iterdir() if p.suffix in (".vtk", ".bgeo"))
    jobs = queue.Queue()
    if args.large:
        jobs.put((pathlib.Path(args.large), 0.5))
    for cube in (float(c) for c in args.cubes.split(",") if c):
        for frame in frames:
            jobs.put((frame, cube))
    if args.busy_all:
        for frame in frames:
            jobs.put((frame, "busy"))
    rows, lock = [], threading.Lock()
    output = pathlib.Path(args.output)

    def write():
        output.write_text(json.dumps(dict(variants={k: [str(v[0]), list(v[1])] for k, v in variants.items()},
                                          repetitions=args.repetitions, rows=rows, busy=busy_result), indent=1))

    busy_result = {}

    def worker(cores):
        while time.time() < deadline:
            try:
                job = jobs.get_nowait()
            except queue.Empty:
                return
            if job[1] == "busy":
                result = busy(args, args.cli, job[0], cores, deadline)
                with lock:
                    busy_result[job[0].name] = result
                    write()
                    print(json.dumps({job[0].name: result}), flush=True)
                continue
            try:
                row = measure(job, cores, args, variants)
            except subprocess.CalledProcessError as error:
                row = dict(frame=job[0].name, cube=job[1], error=error.stderr.decode(errors="replace")[-400:])
            with lock:
                rows.append(row)
                write()
                print(json.dumps({k: row.get(k) for k in ("frame", "cube", "after_vs_paper", "before_vs_paper", "error")}), flush=True)

    threads = [threading.Thread(target=worker, args=(pair,)) for pair in args.pairs.split(";")]
    for t in threads:
        t.start()
    busy_frame = next((f for f in frames if f.name.startswith("hilbert_46843")), frames[0])
    if args.busy_cores:  # empty: no busy check (on a 2-core machine run it alone: --cubes "" --busy-cores 0,1)
        busy_result.update(busy(args, args.cli, busy_frame, args.busy_cores, deadline))
    for t in threads:
        t.join()
    with lock:
        write()
    print(json.dumps(dict(busy=busy_result)))


if __name__ == "__main__":
    main()
