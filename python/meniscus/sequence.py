"""Frame sequences of particle files: pattern detection, folder listing, scene frame -> file resolution.

Free of bpy on purpose: the add-on's handlers use it, and it is tested with plain pytest.

A pattern names one file per frame: a prefix, the frame number, and a suffix (which includes the extension).
Three spellings are accepted and mean the same thing:

    fluid_0001.bgeo       a concrete file; the last run of digits before the extension is the frame number
    fluid_####.bgeo       '#' repeated: the number padded with zeros to that many digits
    fluid_{}.bgeo         splashsurf's spelling: the number without padding

Which name is which frame (detection, listing, the choice between two spellings of one number) is the core's rule
(native/core/io/frame_pattern.h), the same the command line applies.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Dict, Iterable, List, Optional, Tuple

from . import _core

# Out-of-range modes: what a scene frame outside [start, end] (after the offset) shows.
HOLD = "HOLD"    # the first / last frame of the range
LOOP = "LOOP"    # wrap around, so the range repeats forever
BLANK = "BLANK"  # nothing: the surface is empty
OUT_OF_RANGE_MODES = (HOLD, LOOP, BLANK)


@dataclass(frozen=True)
class FramePattern:
    """Where the frames of one sequence live and how their file names are spelled.

    padding is the number of digits zero-padded frame numbers have, 0 when numbers are written without padding.
    """
    directory: str
    prefix: str
    suffix: str
    padding: int = 0

    def file_name(self, frame: int) -> str:
        number = f"{frame:0{self.padding}d}" if self.padding > 0 and frame >= 0 else str(frame)
        return f"{self.prefix}{number}{self.suffix}"

    def path(self, frame: int) -> str:
        return os.path.join(self.directory, self.file_name(frame))

    def pattern_string(self) -> str:
        """The pattern in '####' spelling ('{}' when unpadded), suitable to store and to parse back."""
        marker = "#" * self.padding if self.padding > 0 else "{}"
        return os.path.join(self.directory, f"{self.prefix}{marker}{self.suffix}")

    def match(self, file_name: str) -> Optional[Tuple[int, str]]:
        """The frame number and its digits when file_name belongs to this sequence, else None."""
        frame = _core.match_frame(self.prefix, self.suffix, file_name)
        if frame is None:
            return None
        return frame, file_name[len(self.prefix):len(file_name) - len(self.suffix)]

    def list_frames(self) -> Dict[int, str]:
        """Maps every frame number found in the directory to its path, sorted by frame. Either spelling of a number
        counts ('fluid_7', 'fluid_0007'); when both exist, the one with this pattern's padding wins."""
        frames, _duplicates = _core.list_frames(self.directory, self.prefix, self.suffix, self.padding)
        return frames


def parse_pattern(path: str, sibling_names: Optional[Iterable[str]] = None) -> FramePattern:
    """Detects the frame pattern of a path: a concrete file, or a '####' / '{}' pattern.

    For a concrete file whose number has no leading zero ('fluid_10.vtk'), the padding is ambiguous; the names of
    the other files in the folder decide it (pass sibling_names to avoid listing the folder, e.g. in tests).
    Raises ValueError when the name holds no frame number.
    """
    siblings = None if sibling_names is None else [str(name) for name in sibling_names]
    return FramePattern(*_core.parse_frame_pattern(str(path), siblings))


def nearest_frame(scene_time: float) -> int:
    """The whole frame nearest to a fractional scene time, halves rounded up.

    Motion blur evaluates the scene at shutter subframes (29.75 and 30.25 around frame 30): both must show file
    30, or the surface would be rebuilt from the neighbouring files at every shutter step.
    """
    return int(math.floor(scene_time + 0.5))


def resolve_file_frame(scene_frame: float, frame_offset: int, frame_start: int, frame_end: int,
                       mode: str = HOLD) -> Optional[int]:
    """The file frame number shown at a scene frame (fractional for subframes), or None when nothing is shown.

    file frame = nearest whole scene frame + frame_offset, then [frame_start, frame_end] (file frame numbers,
    inclusive) limits it according to mode (HOLD, LOOP or BLANK). Raises ValueError for an empty range or an
    unknown mode.
    """
    if mode not in OUT_OF_RANGE_MODES:
        raise ValueError(f"unknown out-of-range mode {mode!r}; expected one of {', '.join(OUT_OF_RANGE_MODES)}")
    if frame_start > frame_end:
        raise ValueError(f"frame range is empty: start {frame_start} > end {frame_end}")
    frame = nearest_frame(scene_frame) + int(frame_offset)
    if frame_start <= frame <= frame_end:
        return frame
    if mode == HOLD:
        return frame_start if frame < frame_start else frame_end
    if mode == LOOP:
        # Python's modulo is non-negative for a positive divisor, so frames before the start wrap correctly too.
        return frame_start + (frame - frame_start) % (frame_end - frame_start + 1)
    return None


@dataclass
class _Listing:
    directory_mtime_ns: int
    frames: Dict[int, str]


@dataclass
class SequenceCache:
    """Parsed patterns and folder listings, so a frame change costs one stat() of the folder, not a listing.

    The listing is refreshed when the folder's modification time changes, which picks up frames that a running
    simulation writes while the user scrubs.
    """
    _patterns: Dict[str, FramePattern] = field(default_factory=dict)
    _listings: Dict[FramePattern, _Listing] = field(default_factory=dict)

    def pattern(self, path: str) -> FramePattern:
        pattern = self._patterns.get(path)
        if pattern is None:
            pattern = parse_pattern(path)
            self._patterns[path] = pattern
        return pattern

    def frames(self, pattern: FramePattern) -> Dict[int, str]:
        try:
            mtime = os.stat(pattern.directory or ".").st_mtime_ns
        except OSError:
            self._listings.pop(pattern, None)
            return {}
        listing = self._listings.get(pattern)
        if listing is None or listing.directory_mtime_ns != mtime:
            listing = _Listing(mtime, pattern.list_frames())
            self._listings[pattern] = listing
        return listing.frames

    def clear(self) -> None:
        self._patterns.clear()
        self._listings.clear()


@dataclass(frozen=True)
class FrameLookup:
    """The outcome of resolving a scene frame: which file frame, and its path if the file exists."""
    file_frame: Optional[int]   # None: outside the range in BLANK mode
    path: Optional[str]         # None: nothing to load (blank, or the file is missing)
    expected_path: Optional[str] = None  # what the missing file would be called, for messages


def lookup_frame(frames: Dict[int, str], pattern: FramePattern, scene_frame: float, frame_offset: int,
                 frame_start: int, frame_end: int, mode: str = HOLD) -> FrameLookup:
    """Resolves a scene frame against the listed frames of a sequence."""
    file_frame = resolve_file_frame(scene_frame, frame_offset, frame_start, frame_end, mode)
    if file_frame is None:
        return FrameLookup(None, None)
    path = frames.get(file_frame)
    return FrameLookup(file_frame, path, path or pattern.path(file_frame))


def frame_range(frames: Dict[int, str]) -> Optional[Tuple[int, int]]:
    """First and last available frame numbers, or None for an empty listing."""
    if not frames:
        return None
    numbers: List[int] = list(frames)
    return min(numbers), max(numbers)


def describe_frames(frames: Iterable[int]) -> str:
    """Frame numbers as people write them: [1, 2, 3, 7, 9, 10] -> '1-3, 7, 9-10'."""
    spans: List[List[int]] = []
    for frame in sorted(set(frames)):
        if spans and frame == spans[-1][1] + 1:
            spans[-1][1] = frame
        else:
            spans.append([frame, frame])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in spans)
