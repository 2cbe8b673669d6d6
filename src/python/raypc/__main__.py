"""``python3 -m raypc ARGS``: the ``raypc`` command line, the executable's own program run by the
compiled module (the same subcommands, options, output and exit status)."""
import signal
import sys

from . import _raypc


def main() -> int:
    # Signals act as on the executable: Ctrl-C ends a command at once (``serve`` stops cleanly
    # through its own handler) and a closed pipe ends it quietly, where Python would raise
    # KeyboardInterrupt only after the compiled command returned, and ignore SIGPIPE.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    # "raypc", not this file's path, names the program in --help, as the executable's does.
    return _raypc.main(["raypc", *sys.argv[1:]])


if __name__ == "__main__":
    sys.exit(main())
