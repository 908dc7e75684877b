"""Mesh caches and baking, free of bpy: the add-on's bake operator, its frame handler and scripts all use this.

A cache is a folder of one mesh file per file frame, named by a frame pattern like the particle files
('surface_####.npz'). Frames are numbered like the particle files they come from, so a cache written by the
`meniscus` CLI (`meniscus reconstruct 'in_{}.vtk' -o 'cache/surface_{}.ply'`) plays the same way as one baked here.

Two formats:
- .npz (numpy, uncompressed): what a bake writes by default. Loading is a few memory copies: 0.05 s for a
  1.3 M-triangle surface with normals, weights and velocity, against 0.34-0.47 s for the same mesh as binary PLY
  through the core's reader (measured on the development machine, see bench/results/blender_mesh_update.md).
- .ply / .obj / .vtk: read by the core (what the CLI writes); .ply keeps normals and attributes.
"""
from __future__ import annotations

import os
import threading
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

from . import _core, api

NPZ, PLY = "NPZ", "PLY"
FORMAT_EXTENSIONS = {NPZ: ".npz", PLY: ".ply"}
# Extensions a cache may hold: our own .npz plus what the core's mesh reader understands.
MESH_EXTENSIONS = (".npz", ".ply", ".obj", ".vtk")

# Particle attribute names under which velocities appear in the formats we read (VTK writers, Houdini's 'v').
VELOCITY_NAMES = ("velocity", "v", "vel", "Velocity")
VELOCITY = "velocity"  # the name Cycles reads for motion blur

_NPZ_ATTRIBUTE_PREFIX = "attribute:"


# Reading and writing cached meshes ------------------------------------------------------------------------------

def provenance(source: Optional[str], arguments: dict, wanted: Sequence[str] = ()) -> str:
    """The record (native/core/io/provenance.h) of a mesh built from the particle file `source` with api.reconstruct's
    keyword `arguments` and the wanted attribute names; source None: of the parameters alone (its file is gone)."""
    return _core.provenance_record(dict(arguments), list(wanted), source or "")


def stale_reason(mesh_path: str, record: str) -> str:
    """Why the mesh file was not made as `record` says ("made with particle_radius 0.025, now 0.03", "no record of
    what it was made from"); '' when it was."""
    return _core.provenance_mismatch(mesh_path, record)


def save_mesh(mesh: api.Mesh, path: str, record: Optional[str] = None) -> None:
    """Writes a mesh by extension (.npz here, others through the core), atomically, with its provenance record.

    The file appears under its final name only when complete (written next to it, then renamed): a player that
    scrubs while a bake runs never loads half a file. The old record goes before the mesh is replaced and the new
    one (if given) comes after it: a mesh never sits beside a record of other parameters.
    """
    folder = os.path.dirname(path)
    if folder:
        os.makedirs(folder, exist_ok=True)
    root, extension = os.path.splitext(path)
    # The temporary name keeps the extension: the core chooses the format by it. It does not match the cache's
    # frame pattern ('.partial' sits before the extension, after the digits), so listings never show it.
    temporary = _core.partial_path(path, os.getpid())
    try:
        if extension.lower() == ".npz":
            arrays = {"vertices": np.ascontiguousarray(mesh.vertices, dtype=np.float32),
                      "triangles": np.ascontiguousarray(mesh.triangles, dtype=np.int32)}
            if mesh.normals is not None:
                arrays["normals"] = np.ascontiguousarray(mesh.normals, dtype=np.float32)
            if mesh.quads is not None and len(mesh.quads):
                arrays["quads"] = np.ascontiguousarray(mesh.quads, dtype=np.int32)
            for name, values in mesh.attributes.items():
                values = np.asarray(values)  # whole-number attributes (ids) stay int32
                arrays[_NPZ_ATTRIBUTE_PREFIX + name] = np.ascontiguousarray(
                    values, dtype=np.int32 if values.dtype.kind in "iub" else np.float32)
            with open(temporary, "wb") as stream:  # a file object: np.savez would append '.npz' to a name
                np.savez(stream, **arrays)
        else:
            api.write_mesh(mesh, temporary)
        _core.forget_provenance(path)
        os.replace(temporary, path)
    except BaseException:
        try:
            os.remove(temporary)
        except OSError:
            pass
        raise
    if record is not None:
        _core.write_provenance(path, record)


def writable_folder_problem(folder: str) -> Optional[str]:
    """Why meshes cannot be written into folder (made if missing), or None: checked before a bake reconstructs its
    first frame, so that an unwritable cache costs a message, not a bake's worth of lost frames."""
    try:
        os.makedirs(folder, exist_ok=True)
        probe = os.path.join(folder, f".meniscus-write-check{os.getpid()}")
        with open(probe, "wb"):
            pass
        os.remove(probe)
    except OSError as error:
        return error.strerror or str(error)
    return None


# A temporary file of a writer on another machine sharing the folder has a process id this one cannot check: it goes
# only once untouched for this long (a write takes seconds). The names and the rule live in the core
# (io/partial_files.h), which the command line uses too.
ABANDONED_AFTER_SECONDS = _core.ABANDONED_PARTIAL_SECONDS


def remove_abandoned_partials(folder: str) -> List[str]:
    """Removes the temporary files that killed writers left in folder (their process is gone and the file untouched
    for ABANDONED_AFTER_SECONDS; a live one's stay); returns their names."""
    return _core.remove_abandoned_partials(folder)


def load_mesh(path: str) -> api.Mesh:
    """Reads a cached mesh (.npz of ours, or any mesh file the core reads). Raises api.FormatError or OSError."""
    if path.lower().endswith(".npz"):
        try:
            with np.load(path, allow_pickle=False) as data:
                vertices = data["vertices"].reshape(-1, 3)
                triangles = data["triangles"].reshape(-1, 3)
                normals = data["normals"].reshape(-1, 3) if "normals" in data.files else None
                quads = data["quads"].reshape(-1, 4) if "quads" in data.files else None
                attributes = {key[len(_NPZ_ATTRIBUTE_PREFIX):]: data[key] for key in data.files
                              if key.startswith(_NPZ_ATTRIBUTE_PREFIX)}
        except (KeyError, ValueError, EOFError) as error:  # zip damage, missing arrays, wrong shapes
            raise api.FormatError(f"{path}: not a Meniscus mesh cache file ({error})") from None
        for faces in (triangles, quads if quads is not None else triangles[:0]):
            if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
                raise api.FormatError(f"{path}: face indices out of range")
        return api.Mesh(vertices, triangles, normals, attributes, quads=quads)
    return api.read_mesh(path)


def default_cache_pattern(object_name: str, file_format: str = NPZ) -> str:
    """Where a bake goes when the user chose nothing: next to the .blend ('//'), one folder per object."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in object_name) or "surface"
    return f"//meniscus_cache/{safe}/{safe}_####{FORMAT_EXTENSIONS[file_format]}"


# Reconstruction of one particle file ----------------------------------------------------------------------------

def select_attributes(particle_attributes: Dict[str, np.ndarray], particle_count: int,
                      wanted: Sequence[str] = ()) -> Dict[str, np.ndarray]:
    """The particle attributes to interpolate onto the surface: velocity (for motion blur, under whatever name the
    file uses, stored as 'velocity') plus the wanted names that exist with one value or vector per particle."""
    selected = {}
    for name in VELOCITY_NAMES:
        values = particle_attributes.get(name)
        if values is not None and getattr(values, "shape", None) == (particle_count, 3):
            selected[VELOCITY] = values
            break
    for name in wanted:
        values = particle_attributes.get(name)
        if values is not None and len(values) == particle_count and name not in selected:
            selected[name] = values
    return selected


def parse_attribute_names(text: str) -> List[str]:
    """'density, foam  temperature' -> ['density', 'foam', 'temperature'] (commas or spaces separate)."""
    return [name for name in text.replace(",", " ").split() if name]


def missing_attributes(particle_attributes: Dict[str, np.ndarray], wanted: Sequence[str]) -> List[str]:
    return [name for name in wanted if name not in particle_attributes]


@dataclass
class FrameResult:
    mesh: api.Mesh
    particle_count: int
    seconds: float
    missing_attributes: List[str] = field(default_factory=list)


def reconstruct_positions(positions, particle_attributes, arguments: dict, wanted: Sequence[str] = ()) -> FrameResult:
    """Reconstructs a surface from positions; arguments are api.reconstruct's keyword arguments (radius included)."""
    started = time.perf_counter()
    count = len(positions)
    attributes = select_attributes(particle_attributes, count, wanted)
    if count == 0:  # nothing to surface: an empty mesh rather than an error (a simulation's first frames)
        mesh = api.Mesh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int32), np.zeros((0, 3), np.float32))
    else:
        mesh = api.reconstruct(positions, attributes=attributes, **arguments)
    return FrameResult(mesh, count, time.perf_counter() - started, missing_attributes(particle_attributes, wanted))


def reconstruct_file(path: str, arguments: dict, wanted: Sequence[str] = (),
                     prepare: Optional[Callable] = None) -> FrameResult:
    """Reads one particle file and reconstructs its surface (the time includes reading). prepare(particles, arguments)
    -> (positions, attributes, arguments), when given, turns what was read into what is reconstructed (a fluid
    domain's frame: placed where the domain is now, its fill's domain completed from the file's)."""
    started = time.perf_counter()
    particles = api.read_particles(path)
    positions, attributes = particles.positions, particles.attributes
    if prepare is not None:
        positions, attributes, arguments = prepare(particles, arguments)
    result = reconstruct_positions(positions, attributes, arguments, wanted)
    result.seconds = time.perf_counter() - started
    return result


# Baking ---------------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class BakeTask:
    frame: int          # file frame number (the cache file gets the same number)
    source: str         # particle file
    target: str         # mesh file to write
    arguments: Optional[dict] = None  # this frame's own keyword arguments over the job's (a moving container's box)
    prepare: Optional[Callable] = None  # reconstruct_file's prepare (run in the bake's thread: nothing of bpy)


@dataclass
class BakeJob:
    """Reconstructs a list of frames into mesh files, in a background thread or step by step.

    Touches nothing but files: the Blender operator starts it and polls `done`/`progress` from a timer, so the UI
    stays responsive (the core releases the GIL while it computes). A frame that fails (broken file) is recorded
    in `failures` and the bake goes on; `cancel()` stops after the frame being computed (the core cannot be
    interrupted mid-frame), keeping the frames already written.
    """
    tasks: List[BakeTask]
    arguments: dict
    wanted_attributes: Sequence[str] = ()
    on_frame: Optional[Callable[["BakeJob", BakeTask, Optional[FrameResult]], None]] = None

    completed: int = 0
    failures: Dict[int, str] = field(default_factory=dict)
    seconds: float = 0.0
    cancelled: bool = False
    _cancel: threading.Event = field(default_factory=threading.Event)
    _thread: Optional[threading.Thread] = None
    _finished: threading.Event = field(default_factory=threading.Event)

    @property
    def total(self) -> int:
        return len(self.tasks)

    @property
    def progress(self) -> float:
        return self.completed / self.total if self.tasks else 1.0

    @property
    def done(self) -> bool:
        return self._finished.is_set()

    def cancel(self) -> None:
        self._cancel.set()

    def task_arguments(self, task: BakeTask) -> dict:
        return {**self.arguments, **task.arguments} if task.arguments else self.arguments

    def stale_frames(self) -> Dict[int, str]:
        """Frames not baked by this job (cancelled before them) whose file in the cache was made otherwise, with
        why: they must not play as if this bake had made them."""
        stale = {}
        for task in self.tasks[self.completed:]:
            if os.path.exists(task.target):
                try:
                    reason = stale_reason(task.target, provenance(task.source, self.task_arguments(task),
                                                                  self.wanted_attributes))
                except (api.FormatError, OSError) as error:  # the particle file is gone meanwhile
                    reason = str(error)
                if reason:
                    stale[task.frame] = reason
        return stale

    def step(self) -> bool:
        """Bakes the next frame; returns False when there is nothing left (finished or cancelled)."""
        if self._cancel.is_set():
            self.cancelled = self.completed < self.total
            self._finished.set()
            return False
        if self.completed >= self.total:
            self._finished.set()
            return False
        task = self.tasks[self.completed]
        started = time.perf_counter()
        result = None
        try:
            arguments = self.task_arguments(task)
            try:  # before reading (see native/core/io/provenance.h); without one the frame counts as stale later
                record = provenance(task.source, arguments, self.wanted_attributes)
            except (api.FormatError, OSError):
                record = None  # the reader says what is wrong with the file
            result = reconstruct_file(task.source, arguments, self.wanted_attributes, task.prepare)
            save_mesh(result.mesh, task.target, record)
        except (api.FormatError, OSError, MemoryError, ValueError) as error:
            self.failures[task.frame] = str(error) or type(error).__name__
            # A stale file from an earlier bake would play as if this frame had worked: remove it.
            _core.forget_provenance(task.target)
            try:
                os.remove(task.target)
            except OSError:
                pass
        self.seconds += time.perf_counter() - started
        self.completed += 1
        if self.on_frame is not None:
            self.on_frame(self, task, result)
        return True

    def run(self) -> "BakeJob":
        """Bakes every frame in the calling thread (scripts, command line)."""
        while self.step():
            pass
        self._finished.set()
        return self

    def start(self) -> "BakeJob":
        """Bakes in a daemon thread (a Blender quit does not wait for it); poll `done`."""
        def work():
            try:
                self.run()
            except BaseException as error:  # anything unexpected: end the job rather than leave the poller waiting
                self.failures[-1] = f"{type(error).__name__}: {error}"
            finally:
                self._finished.set()

        self._thread = threading.Thread(target=work, name="meniscus-bake", daemon=True)
        self._thread.start()
        return self

    def wait(self, timeout: Optional[float] = None) -> bool:
        return self._finished.wait(timeout)
