"""The `meniscus` command line (console script of the wheel): the native tool's code, run inside Python, plus the
farm commands that need Python (docs/farm.md):

    meniscus farm openjd INPUT -o OUTPUT -s FIRST -e LAST [--chunk-size N] [--parameters FILE | flags] --bundle DIR
    meniscus reconstruct ... --scheduler ADDRESS     (a Dask cluster; pip install "meniscus[dask]")

Both hand the pipeline flags to the native command line's --save-parameters, so they are parsed and checked by the
one parser every other command uses, and the job carries the resulting parameters file.
"""
import argparse
import json
import os
import shlex
import sys
import tempfile

from . import _core


def _save_parameters(reconstruct_arguments):
    """The parameters file the native parser makes of these reconstruct arguments, as (text, dict); None when it
    refused them (it has said why on stderr)."""
    from .farm import run_cli

    with tempfile.TemporaryDirectory(prefix="meniscus-") as folder:
        path = os.path.join(folder, "parameters.json")
        if run_cli(["reconstruct", *reconstruct_arguments, "--save-parameters", path, "-q"]) != 0:
            return None
        with open(path, encoding="utf-8") as f:
            text = f.read()
    return text, json.loads(text)


def _farm(argv) -> int:
    from . import farm

    parser = argparse.ArgumentParser(
        prog="meniscus farm openjd",
        description="Write an Open Job Description job bundle (AWS Deadline Cloud: deadline bundle submit DIR; any "
                    "OpenJD runner: openjd run DIR/template.yaml). Pipeline flags (-r, -c, ...) are those of "
                    "meniscus reconstruct.")
    parser.add_argument("engine", choices=["openjd"], help="the job format")
    parser.add_argument("input", nargs="?", help="particle files, {} or #### for the frame number")
    parser.add_argument("-o", "--output-file", dest="output", help="mesh files, {} or #### for the frame number")
    parser.add_argument("-s", "--start-index", type=int, dest="start", help="first frame")
    parser.add_argument("-e", "--end-index", type=int, dest="end", help="last frame")
    parser.add_argument("--chunk-size", type=int, default=1, help="frames per task (default 1)")
    parser.add_argument("--parameters", help="a parameters file (flags given beside it win)")
    parser.add_argument("--bundle", required=True, help="folder the job bundle is written to")
    parser.add_argument("--meniscus-command", default="meniscus",
                        help="the meniscus command on the workers (default: meniscus, found on their PATH)")
    parser.add_argument("--name", help="job name (default: from the input name and frames)")
    options, flags = parser.parse_known_args(argv)
    if options.chunk_size < 1:
        parser.error(f"--chunk-size must be at least 1, got {options.chunk_size}")
    arguments = [options.input] if options.input else []
    for flag, value in (("-o", options.output), ("-s", options.start), ("-e", options.end),
                        ("--parameters", options.parameters)):
        if value is not None:
            arguments += [flag, str(value)]
    saved = _save_parameters(arguments + flags)
    if saved is None:
        return 2
    text, document = saved
    missing = [name for name in ("output", "start", "end") if name not in document]
    if missing:
        parser.error("needs " + ", ".join({"output": "-o", "start": "-s", "end": "-e"}[m] for m in missing) +
                     " (or those keys in --parameters)")
    # Absolute paths in the job: workers run in other folders.
    document["input"], document["output"] = os.path.abspath(document["input"]), os.path.abspath(document["output"])
    survey = farm.survey_outputs(document, document["start"], document["end"])
    if not survey.frames:
        sys.stderr.write(f"error: no particle files match '{document['input']}' in frames "
                         f"{document['start']}-{document['end']}: the job would only fail\n")
        return 2
    for line in survey.lines():
        print(line)
    text = json.dumps(document, indent=2) + "\n"
    bundle = farm.write_openjd_bundle(options.bundle, text, document["input"], document["output"], document["start"],
                                      document["end"], options.chunk_size, options.meniscus_command, options.name)
    print(f"{bundle.directory}: {len(bundle.tasks)} tasks of up to {options.chunk_size} frames "
          f"({document['start']}-{document['end']}). Run it here with:\n  openjd {' '.join(map(shlex.quote, bundle.openjd_arguments()))}"
          f"\nor submit it to AWS Deadline Cloud with:\n  deadline bundle submit {shlex.quote(bundle.directory)}")
    return 0


def _reconstruct_on_scheduler(argv) -> int:
    from . import farm
    from .sequence import parse_pattern

    arguments, address, quiet = list(argv[1:]), None, False
    while "--scheduler" in arguments:
        at = arguments.index("--scheduler")
        if at + 1 >= len(arguments):
            sys.stderr.write("error: --scheduler takes the address of a Dask scheduler (tcp://host:8786)\n")
            return 2
        address = arguments[at + 1]
        del arguments[at:at + 2]
    stats_path = arguments[arguments.index("--stats") + 1] if "--stats" in arguments[:-1] else None
    skip_existing = "--skip-existing" in arguments
    quiet = "-q" in arguments or "--quiet" in arguments
    saved = _save_parameters(arguments)
    if saved is None:
        return 2
    text, document = saved
    first, last = document.get("start"), document.get("end")
    if first is None or last is None:
        frames = parse_pattern(document["input"]).list_frames()
        if not frames:
            sys.stderr.write(f"error: no frames match '{document['input']}'\n")
            return 2
        first = min(frames) if first is None else first
        last = max(frames) if last is None else last
    if skip_existing:
        for line in farm.survey_outputs(document, first, last).lines():
            sys.stderr.write(line + "\n")
    try:
        from distributed import Client
    except ImportError:
        sys.stderr.write('error: --scheduler needs Dask: pip install "meniscus[dask]"\n')
        return 2
    with Client(address, timeout=30) as client:
        run = farm.reconstruct_on_cluster(client, text, first, last, skip_existing=skip_existing, progress=not quiet)
    for error in run.errors:
        sys.stderr.write(f"error: {error}\n")
    if stats_path:
        with open(stats_path, "w", encoding="utf-8", newline="\n") as f:
            json.dump({"frames": run.records, "failed": sorted(run.failed), "failed_frames": len(run.failed),
                       "total_seconds": run.seconds, "scheduler": address}, f, indent=2)
    if run.failed:
        sys.stderr.write(f"{len(run.failed)} of {last - first + 1} frames failed: "
                         f"{', '.join(map(str, sorted(run.failed)))}\n")
    return 0 if run.ok else 1


def main(argv=None) -> int:
    """Runs `meniscus ARGS...`; returns the exit status (0 ok, 1 a frame failed, 2 bad usage or input, 130 Ctrl-C)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["farm"]:
        return _farm(argv[1:])
    if argv[:1] == ["reconstruct"] and "--scheduler" in argv:
        return _reconstruct_on_scheduler(argv)
    arguments = ["meniscus", *argv]
    sys.stdout.flush()  # the native code writes to the same descriptors: keep Python's pending output first
    sys.stderr.flush()
    try:
        return _core.run_cli(arguments)
    except KeyboardInterrupt:  # between frames; the frames written so far stay
        return 130


if __name__ == "__main__":
    sys.exit(main())
