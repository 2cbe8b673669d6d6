"""``python3 -m raypc ARGS``: the ``raypc`` command line, the executable's own program run by the
compiled module (the same subcommands, options, output and exit status)."""
import os
import signal
import sys

from . import _raypc


def main() -> int:
    # Signals act as on the executable: Ctrl-C ends a command at once (``serve`` stops cleanly
    # through its own handler) and a closed pipe ends it quietly, where Python would raise
    # KeyboardInterrupt only after the compiled command returned, and ignore SIGPIPE.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    # An installed package carries the UI (and the coastlines beside it) and the example states:
    # `serve` and `render` take them from there unless $RAYPC_ASSETS / $RAYPC_EXAMPLES or the
    # options say otherwise (in the build tree there are none, and the source tree's are found).
    here = os.path.dirname(os.path.abspath(__file__))
    if os.path.isfile(os.path.join(here, "web", "index.html")):
        os.environ.setdefault("RAYPC_ASSETS", os.path.join(here, "web"))
    if os.path.isdir(os.path.join(here, "examples")):
        os.environ.setdefault("RAYPC_EXAMPLES", os.path.join(here, "examples"))
    # "raypc", not this file's path, names the program in --help, as the executable's does.
    return _raypc.main(["raypc", *sys.argv[1:]])


if __name__ == "__main__":
    sys.exit(main())
