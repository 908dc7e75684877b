"""How threads that wait at OpenMP barriers behave: they spin briefly, then sleep (native/core/base/waiting.h says
why; its constants and these must agree, which tests/python/test_waiting_threads.py checks).

GNU libgomp reads its policy only when it loads, with the core: this module sets it first. It imports nothing of the
package, so the Blender add-on can load this file by its path before the package (which loads the core) is
imported. A policy the user set stays as it is.
"""
import os

BARRIER_SPIN_COUNT = "10000"  # waiting.h: kBarrierSpinCount (GOMP_SPINCOUNT, GNU libgomp)
BARRIER_BLOCK_MILLISECONDS = 1  # waiting.h: kBarrierBlockMilliseconds (KMP_BLOCKTIME, LLVM's runtime)


def wait_briefly_at_barriers(environment=os.environ):
    """Sets the brief spin in environment unless the user chose a policy there."""
    if "OMP_WAIT_POLICY" not in environment:
        environment.setdefault("GOMP_SPINCOUNT", BARRIER_SPIN_COUNT)
        environment.setdefault("KMP_BLOCKTIME", str(BARRIER_BLOCK_MILLISECONDS))
