"""Renames over files that another program may hold open: the add-on's one way to replace a file or folder.

Windows refuses to rename a file, or to rename another over it, while a program holds it open without delete sharing
(FILE_SHARE_DELETE): most readers, Python's open() among them, an image viewer, a virus scanner looking at a file just
written. Such a program usually lets go within moments, so a refused rename is tried again for a bounded time, and
then the last refusal is raised with the file's name and the time waited. Elsewhere a rename is never refused for
that, and this is a plain os.replace. bpy-free: the core's copy (core_copy) uses it before anything else is loaded.
"""
import os
import time

# How long a refused replacement is tried again: a reader's usual time, as the core's own writers wait.
WAIT_SECONDS = 5.0
_RETRY_INTERVAL_SECONDS = 0.1


class StillHeldOpen(PermissionError):
    """The rename was still refused after WAIT_SECONDS; strerror ends with the time waited."""

    def __str__(self):  # the paths as they are written (OSError's own str() quotes them, doubling '\' on Windows)
        return f"cannot move {self.filename} to {self.filename2} ({self.strerror})"


def replace(source, target, otherwise=None):
    """os.replace(source, target), tried again while Windows refuses it (PermissionError) for up to WAIT_SECONDS.

    otherwise: called after each refusal; returning True means the caller's goal was reached another way (the file
    written over in place, another process's copy already there) and ends the wait without the rename. A
    PermissionError it raises counts as one more refusal. Raises StillHeldOpen after the wait; any other OSError at
    once."""
    deadline = time.monotonic() + WAIT_SECONDS
    while True:
        try:
            os.replace(source, target)
            return
        except PermissionError as error:
            refusal = error
        try:
            if otherwise is not None and otherwise():
                return
        except PermissionError as error:
            refusal = error
        if time.monotonic() >= deadline:
            reason = refusal.strerror or str(refusal)
            raise StillHeldOpen(refusal.errno, f"{reason}; waited {WAIT_SECONDS:g} s", source, None,
                                target) from refusal
        time.sleep(_RETRY_INTERVAL_SECONDS)
