"""The `meniscus` command line (console script of the wheel): the native tool's code, run inside Python."""
import sys

from . import _core


def main(argv=None) -> int:
    """Runs `meniscus ARGS...`; returns the exit status (0 ok, 1 a frame failed, 2 bad usage or input, 130 Ctrl-C)."""
    arguments = ["meniscus", *(sys.argv[1:] if argv is None else argv)]
    sys.stdout.flush()  # the native code writes to the same descriptors: keep Python's pending output first
    sys.stderr.flush()
    try:
        return _core.run_cli(arguments)
    except KeyboardInterrupt:  # between frames; the frames written so far stay
        return 130


if __name__ == "__main__":
    sys.exit(main())
