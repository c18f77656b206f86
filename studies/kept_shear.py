"""A packing shear that keeps what it finished, so that a rerun resumes.

Each segment of the shear (the branch up to a plastic event passed, models/packing/segments.py)
is written to DIR as it is passed, keyed by everything its result depends on (resume_key); a
rerun of the same shear, interrupted or failed, reads them back (finished_segments) and goes
on after them with the same result. A segment file it cannot read, or one written for other
inputs or code, is computed again with those after it.
"""
from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

from diskfriction.scenes.packing import PackingScene
from diskfriction.studies.cluster import code_version, task_key
from diskfriction.words import count

SEGMENT_FILE = "segment-{:04d}.npz"
"""A finished segment's file in DIR (its index in the run)."""


def resume_key(scene: PackingScene, window, detection: str, plastic_events: int) -> str:
    """What a shear's segments depend on: the scene's physics (its matrix included), the
    window, the detection, the plastic events it may pass and the code version
    (studies.cluster.code_version). Not the scan workers: a run resumed on other workers is
    the same shear."""
    return task_key(scene.physics_fields(), window, detection, plastic_events, code_version())


def finished_segments(directory: Path, key: str) -> tuple[list, str]:
    """(the segments of an earlier run with `key` in `directory`, in order from the first, up
    to the first one missing, unreadable or written for another key; why that one is not read,
    "" if it is missing). The run computes that segment and those after it again and writes
    them over the files."""
    from diskfriction.models.packing.segments import SegmentFileError, load_segment

    done = []
    while (directory / SEGMENT_FILE.format(len(done))).exists():
        try:
            done.append(load_segment(directory / SEGMENT_FILE.format(len(done)), key))
        except SegmentFileError as error:
            return done, str(error)
    return done, ""


@dataclass(frozen=True)
class KeptSegments:
    """The segments kept in `directory` for the shear keyed `key`: those an earlier run
    finished (`done`, in order), and why the next one on disk was not read (`unread`, "" if
    none was there)."""

    directory: Path
    key: str
    done: tuple
    unread: str

    def resumed(self) -> str:
        """What the shear's progress line adds: where it resumes, and what it computes again."""
        after = (f" (resumed after {count(len(self.done), 'segment')}, at gamma = "
                 f"{self.done[-1].plastic[0].after[3]:.6g})" if self.done else "")
        return after + (f"; computed again: {self.unread}" if self.unread else "")

    def save(self, segment) -> None:
        """Write a segment the shear just finished (the shear's on_segment)."""
        from diskfriction.models.packing.segments import save_segment

        save_segment(self.directory / SEGMENT_FILE.format(segment.segment[-1]), segment, self.key)

    def finished(self) -> bool:
        """Whether a rerun has segments to resume from."""
        return any(self.directory.glob(SEGMENT_FILE.replace("{:04d}", "*")))

    def release(self, keep: bool) -> None:
        """Remove the directory, unless `keep` and a rerun has segments to resume from."""
        if not (keep and self.finished()):
            shutil.rmtree(self.directory, ignore_errors=True)


def kept_segments(directory: Path, scene: PackingScene, window, detection: str,
                  plastic_events: int) -> KeptSegments:
    """The segments kept in `directory` for this shear (resume_key), read back."""
    key = resume_key(scene, window, detection, plastic_events)
    done, unread = finished_segments(directory, key)
    return KeptSegments(directory, key, tuple(done), unread)
