"""Sequences on a farm: the parameters file, Open Job Description bundles (AWS Deadline Cloud, any OpenJD runner)
and Dask clusters (SLURM, PBS, SGE through dask-jobqueue). Free of bpy: the Blender add-on exports jobs with it.

Every farm task runs the same command, `meniscus reconstruct --parameters FILE --frames A-B --skip-existing`: the
core in its own process with its threads, reading particle files from and writing meshes to a file system the
machines share. Meshes are written under a temporary name and renamed when complete, so a preempted task leaves
nothing half-written and its re-run redoes only the frames that are missing. See docs/farm.md.
"""
from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from . import _core
from .parameters import BY_NAME, PARAMETERS, convert

PARAMETERS_FILE_VERSION = 1


# ---- the parameters file (the command line's --parameters / --save-parameters, native/cli/parameters_file.h) ---

def parameters_file_text(parameters: Dict[str, object], input: Optional[str] = None, output: Optional[str] = None,
                         start: Optional[int] = None, end: Optional[int] = None,
                         attributes: Optional[Sequence[str]] = None) -> str:
    """The JSON the command line reads with --parameters: every schema parameter (those not given at their
    defaults), with the input and output patterns and the frame range. Raises ValueError naming a parameter that is
    unknown or whose value is not allowed."""
    for name in parameters:
        if name not in BY_NAME:
            raise ValueError(f"{name}: unknown parameter (the parameters are: {', '.join(BY_NAME)})")
    values = {}
    for p in PARAMETERS:
        value = parameters.get(p.name, None if p.type == "vector3" else p.default)
        if value is not None or p.type == "vector3":
            problem = p.problem(value)
            if problem:
                raise ValueError(f"{p.name}: {problem}")
        values[p.name] = None if value is None else (list(convert(p, value)) if p.type == "vector3" else convert(p, value))
    for key, frame in (("start", start), ("end", end)):
        problem = None if frame is None else _core.frame_number_problem(int(frame))
        if problem:
            raise ValueError(f"{key}: {problem}")
    if start is not None and end is not None and _core.frame_range_problem(int(start), int(end)):
        raise ValueError(f"end: {_core.frame_range_problem(int(start), int(end))}")
    document = {"meniscus_parameters": PARAMETERS_FILE_VERSION}
    for key, value in (("input", input), ("output", output), ("start", start), ("end", end)):
        if value is not None:
            document[key] = value if key in ("input", "output") else int(value)
    if attributes:
        document["interpolate_attributes"] = list(attributes)
    document["parameters"] = values
    return json.dumps(document, indent=2) + "\n"


def read_parameters_file(path) -> dict:
    """The parameters file as a dict (checked by the command line when it runs; this only reads the JSON)."""
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def run_cli(arguments: Sequence[str]) -> int:
    """The `meniscus` command line in this process: its exit status (0 done, 1 some frames failed, 2 usage)."""
    sys.stdout.flush()
    sys.stderr.flush()
    return _core.run_cli(["meniscus", *map(str, arguments)])


def chunks(first: int, last: int, size: int) -> List[Tuple[int, int]]:
    """Contiguous chunks [a, b] of at most size frames covering first..last."""
    if size < 1:
        raise ValueError(f"chunk size must be at least 1, got {size}")
    if last < first:
        raise ValueError(f"frame range is empty: first {first} > last {last}")
    return [(a, min(a + size - 1, last)) for a in range(first, last + 1, size)]


@dataclass
class OutputSurvey:
    """What a job over a parameters file's frames finds before it runs: the frames with a particle file, those
    without (their tasks would fail), and those whose output exists but was made with other parameters or another
    particle file (native/core/io/provenance.h), with why: --skip-existing redoes them."""
    frames: List[int]
    missing: List[int]
    stale: Dict[int, str]

    def lines(self) -> List[str]:
        from .sequence import describe_frames

        lines = []
        if self.missing:
            lines.append(f"warning: {len(self.missing)} frames have no particle file and will fail: "
                         f"{describe_frames(self.missing)}")
        if self.stale:
            first = min(self.stale)
            lines.append(f"{len(self.stale)} frames will be redone, their output being from another run "
                         f"({describe_frames(self.stale)}; frame {first}: {self.stale[first]})")
        return lines


def survey_outputs(document: dict, first: int, last: int) -> OutputSurvey:
    """Surveys frames first..last of a parameters file (as a dict) against its input and output folders."""
    from .sequence import parse_pattern

    input_pattern = parse_pattern(document["input"])
    inputs = input_pattern.list_frames()
    output = document.get("output")
    arguments = {name: value for name, value in document.get("parameters", {}).items()}
    attributes = list(document.get("interpolate_attributes", []))
    frames, stale = [], {}
    # Only the frames that exist are looked at: a range refused as too long never gets here (the parameters file's
    # range is bounded), and the listing is one folder read.
    for frame in sorted(f for f in inputs if first <= f <= last):
        frames.append(frame)
        if not output:
            continue
        if "{}" in output:  # the input's digits as written, as the command line names its outputs
            digits = input_pattern.match(os.path.basename(inputs[frame]))[1]
            target = output.replace("{}", digits, 1)
        else:
            target = parse_pattern(output, sibling_names=()).path(frame)
        if os.path.exists(target):
            reason = _core.provenance_mismatch(target, _core.provenance_record(arguments, attributes, inputs[frame]))
            if reason:
                stale[frame] = reason
    present = set(frames)  # the range is bounded (parameters files and flags are checked before a job is written)
    missing = [frame for frame in range(first, last + 1) if frame not in present]
    return OutputSurvey(frames, missing, stale)


# ---- Open Job Description bundles --------------------------------------------------------------------------------

def _yaml(value, indent: int = 0) -> str:
    """Block-style YAML of dicts, lists and scalars; scalars are written as JSON, which YAML reads as they are."""
    pad = "  " * indent
    if isinstance(value, dict):
        lines = []
        for key, item in value.items():
            if isinstance(item, (dict, list)) and item:
                lines.append(f"{pad}{key}:\n{_yaml(item, indent + 1)}")
            else:
                lines.append(f"{pad}{key}: {_yaml(item)}")
        return "\n".join(lines)
    if isinstance(value, list):
        if not value:
            return "[]"
        lines = []
        for item in value:
            if isinstance(item, dict) and item:
                inner = _yaml(item, indent + 1)
                lines.append(f"{pad}- {inner.lstrip()}")
            else:
                lines.append(f"{pad}- {_yaml(item)}")
        return "\n".join(lines)
    if value == {}:
        return "{}"
    return json.dumps(value)


def _split(pattern: str) -> Tuple[str, str]:
    """A pattern's absolute folder and its file name (the name keeps the {} or #### of the frame number)."""
    path = os.path.abspath(pattern)
    return os.path.dirname(path), os.path.basename(path)


@dataclass
class Bundle:
    directory: str
    template: str
    parameter_values: str
    asset_references: str
    parameters_file: str
    tasks: List[Tuple[int, int]]
    openjd_parameters: List[str]  # KEY=VALUE of the folders outside the bundle, which OpenJD cannot default

    def openjd_arguments(self) -> List[str]:
        """`openjd run`'s arguments that run the whole job here."""
        return ["run", self.template, *[a for value in self.openjd_parameters for a in ("-p", value)]]


def write_openjd_bundle(bundle_dir, parameters_text: str, input_pattern: str, output_pattern: str, first: int,
                        last: int, chunk_size: int = 1, meniscus_command: str = "meniscus",
                        job_name: Optional[str] = None) -> Bundle:
    """Writes a job bundle (the folder `deadline bundle submit` and `openjd run DIR/template.yaml` take): a
    jobtemplate-2023-09 template whose one step reconstructs contiguous chunks of chunk_size frames, its
    parameter_values.yaml and asset_references.yaml, and the parameters file the tasks read (parameters.json).

    The input and output folders are PATH job parameters (dataFlow IN and OUT), so that Deadline Cloud's job
    attachments upload and download them and path mapping rewrites them for workers with other mounts. Every job
    parameter has a default but a folder outside the bundle, which OpenJD does not allow to default (its value is in
    parameter_values.yaml, and Bundle.openjd_arguments() gives openjd run's). meniscus_command is the command workers run (the
    executable, or the console script of `pip install meniscus`)."""
    frames = chunks(first, last, chunk_size)
    bundle = os.path.abspath(bundle_dir)
    os.makedirs(bundle, exist_ok=True)
    input_dir, input_name = _split(input_pattern)
    output_dir, output_name = _split(output_pattern)
    os.makedirs(output_dir, exist_ok=True)
    parameters_file = os.path.join(bundle, "parameters.json")
    with open(parameters_file, "w", encoding="utf-8", newline="\n") as f:
        f.write(parameters_text)
    name = job_name or f"Meniscus {input_name} {first}-{last}"

    def path_parameter(name, kind, flow, path, description):
        # OpenJD joins a PATH default to the template's folder and refuses absolute ones and ones outside it: a
        # folder inside the bundle gets a default, others their value from parameter_values.yaml (Deadline Cloud)
        # or openjd run's -p (openjd_arguments).
        definition = {"name": name, "type": "PATH", "objectType": kind, "dataFlow": flow, "description": description}
        try:
            relative = os.path.relpath(path, bundle)
        except ValueError:  # another drive (Windows)
            relative = None
        if relative is not None and relative != os.pardir and not relative.startswith(os.pardir + os.sep):
            definition["default"] = relative.replace(os.sep, "/")
        else:
            needed.append(f"{name}={path}")
        return definition

    needed = []
    template = {
        "specificationVersion": "jobtemplate-2023-09",
        "extensions": ["TASK_CHUNKING"],
        "name": name,
        "parameterDefinitions": [
            path_parameter("InputFolder", "DIRECTORY", "IN", input_dir, "Folder of the particle files"),
            path_parameter("OutputFolder", "DIRECTORY", "OUT", output_dir, "Folder the meshes are written to"),
            path_parameter("ParametersFile", "FILE", "IN", parameters_file, "Meniscus parameters file (JSON)"),
            {"name": "InputName", "type": "STRING", "default": input_name,
             "description": "Particle file name; {} or #### stands for the frame number"},
            {"name": "OutputName", "type": "STRING", "default": output_name,
             "description": "Mesh file name; {} or #### stands for the frame number"},
            {"name": "Frames", "type": "STRING", "default": f"{first}-{last}", "description": "Frames to reconstruct"},
            {"name": "ChunkSize", "type": "INT", "default": chunk_size, "minValue": 1,
             "description": "Frames per task (contiguous)"},
            {"name": "Threads", "type": "INT", "default": 0, "minValue": 0,
             "description": "Threads per task; 0: all of the worker host's cores"},
            {"name": "MeniscusCommand", "type": "STRING", "default": meniscus_command,
             "description": "The meniscus command on the workers"},
        ],
        "steps": [{
            "name": "Reconstruct",
            "parameterSpace": {"taskParameterDefinitions": [{
                "name": "Frame", "type": "CHUNK[INT]", "range": "{{Param.Frames}}",
                "chunks": {"defaultTaskCount": "{{Param.ChunkSize}}", "rangeConstraint": "CONTIGUOUS"},
            }]},
            "script": {"actions": {"onRun": {
                "command": "{{Param.MeniscusCommand}}",
                # --skip-existing: a re-queued task redoes only the frames it had not finished. Exit 1 (a frame
                # failed, named on stderr) fails the task; the frames of other tasks are unaffected.
                "args": ["reconstruct", "--parameters", "{{Param.ParametersFile}}",
                         "{{Param.InputFolder}}/{{Param.InputName}}", "-o", "{{Param.OutputFolder}}/{{Param.OutputName}}",
                         "--frames", "{{Task.Param.Frame}}", "--threads", "{{Param.Threads}}", "--skip-existing", "-q"],
            }}},
        }],
    }
    values = {"parameterValues": [
        {"name": "InputFolder", "value": input_dir},
        {"name": "OutputFolder", "value": output_dir},
        {"name": "ParametersFile", "value": parameters_file},
        {"name": "Frames", "value": f"{first}-{last}"},
        {"name": "ChunkSize", "value": chunk_size},
    ]}
    assets = {"assetReferences": {
        "inputs": {"directories": [input_dir], "filenames": [parameters_file]},
        "outputs": {"directories": [output_dir]},
        "referencedPaths": [],
    }}
    header = "# Written by meniscus farm openjd (python/meniscus/farm.py); docs/farm.md says how to run it.\n"
    paths = {}
    for file_name, document in (("template.yaml", template), ("parameter_values.yaml", values),
                                ("asset_references.yaml", assets)):
        paths[file_name] = os.path.join(bundle, file_name)
        with open(paths[file_name], "w", encoding="utf-8", newline="\n") as f:
            f.write(header + _yaml(document) + "\n")
    return Bundle(bundle, paths["template.yaml"], paths["parameter_values.yaml"], paths["asset_references.yaml"],
                  parameters_file, frames, needed)


# ---- Dask ----------------------------------------------------------------------------------------------------------

def _reconstruct_chunk(parameters_text: str, first: int, last: int, skip_existing: bool) -> List[dict]:
    """Runs on a Dask worker: frames first..last in the worker's process, the meshes written to their output
    paths. Returns one small record per frame (no mesh travels back): frame, and failed or skipped when so."""
    with tempfile.TemporaryDirectory(prefix="meniscus-task-") as folder:
        parameters_file = os.path.join(folder, "parameters.json")
        stats_file = os.path.join(folder, "stats.json")
        with open(parameters_file, "w", encoding="utf-8", newline="\n") as f:
            f.write(parameters_text)
        arguments = ["reconstruct", "--parameters", parameters_file, "--frames", f"{first}-{last}", "--stats", stats_file, "-q"]
        status = run_cli(arguments + (["--skip-existing"] if skip_existing else []))
        if status not in (0, 1) or not os.path.exists(stats_file):
            raise RuntimeError(f"frames {first}-{last}: meniscus reconstruct exited with status {status} "
                               "(see the worker's log)")
        with open(stats_file, encoding="utf-8") as f:
            report = json.load(f)
    records = []
    for frame in report["frames"]:
        record = {"frame": frame.get("frame"), "output": frame.get("output")}
        for key in ("failed", "skipped", "redone"):
            if key in frame:
                record[key] = frame[key]
        if "seconds" in frame:
            record["seconds"] = frame["seconds"]["total"]
        records.append(record)
    return records


@dataclass
class ClusterRun:
    """What a cluster run did: every frame's record, the failed frames with their messages."""
    records: List[dict] = field(default_factory=list)
    failed: Dict[int, str] = field(default_factory=dict)
    errors: List[str] = field(default_factory=list)  # chunks that did not run at all (usage errors, lost 3 times)
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return not self.failed and not self.errors


def _progress(done: int, total: int, started: float, label: str) -> None:
    width = 30
    filled = width * done // max(total, 1)
    elapsed = time.monotonic() - started
    sys.stderr.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {done}/{total} {elapsed:5.1f}s {label:<24.24}")
    if done == total:
        sys.stderr.write("\n")
    sys.stderr.flush()


def reconstruct_on_cluster(client, parameters_text: str, first: int, last: int, chunk_size: int = 1,
                           skip_existing: bool = False, progress: bool = True) -> ClusterRun:
    """Reconstructs frames first..last of the parameters file's sequence on a Dask cluster (client: a
    distributed.Client). Each chunk of chunk_size frames is one task; a worker runs it in its own process with its
    threads and writes the meshes to the output paths (a file system the workers share); only small records come
    back. A failing frame is reported and the others finish; a worker lost mid-task has its tasks run again on
    another (Dask's allowed-failures, 3 by default), and the temporary-name writes keep a killed one's mesh out of
    the output names."""
    from distributed import as_completed  # optional dependency: pip install "meniscus[dask]"

    started = time.monotonic()
    futures = {}
    for a, b in chunks(first, last, chunk_size):
        # pure=False: a re-submitted job runs again instead of reusing a finished future of the same arguments.
        future = client.submit(_reconstruct_chunk, parameters_text, a, b, skip_existing, pure=False,
                               key=f"meniscus-frames-{a}-{b}-{os.getpid()}-{time.time_ns()}")
        futures[future] = (a, b)
    run = ClusterRun()
    done = 0
    for future in as_completed(list(futures)):
        a, b = futures[future]
        try:
            records = future.result()
        except Exception as error:  # noqa: BLE001 - a chunk that did not run is reported, the others go on
            run.errors.append(f"frames {a}-{b}: {error}")
            records = []
        for record in records:
            run.records.append(record)
            if "failed" in record:
                run.failed[record["frame"]] = record["failed"]
                if progress:
                    sys.stderr.write(f"\nerror: frame {record['frame']}: {record['failed']}\n")
        done += 1
        if progress:
            _progress(done, len(futures), started, f"frames {a}-{b}")
    run.records.sort(key=lambda r: r["frame"])
    run.seconds = time.monotonic() - started
    return run
