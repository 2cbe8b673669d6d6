"""The package as pip installs it (pyproject.toml, setup.py): a wheel built from the CMake build tree
without compiling anything again, installed into a fresh virtual environment, imported from outside
the source tree; its version and entry points, `python -m raypc` against the raypc executable, the
UI and the example states served from inside the package, and test_dataset.py on the installed
package."""
import hashlib
import json
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from conftest import RAYPC_EXE

SOURCE = Path(os.environ["RAYPC_SOURCE_DIR"])
BUILD = Path(os.environ["RAYPC_BUILD_DIR"])
# The tests' environment without the build tree on PYTHONPATH: the venv's own raypc only.
CLEAN_ENV = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}


def digest(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    """Builds the wheel (timed), installs it into a new venv that sees Debian's packages; returns
    the venv's python."""
    work = tmp_path_factory.mktemp("wheel")
    built = sorted((BUILD / "python" / "raypc").glob("_raypc*.so"))
    assert len(built) == 1, built
    before = (built[0].stat().st_mtime_ns, digest(built[0]))

    start = time.monotonic()
    out = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-build-isolation", "--no-deps", "--no-index",
                          "--no-cache-dir", "-v", "-w", str(work / "dist"), str(SOURCE)],
                         env=dict(CLEAN_ENV, RAYPC_BUILD_DIR=str(BUILD)), capture_output=True, text=True, timeout=900)
    seconds = time.monotonic() - start
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-4000:]
    print(f"pip wheel from the build tree: {seconds:.1f} s")
    # The build tree was up to date (ctest runs after the build): the wheel's build compiled nothing.
    assert "ninja: no work to do." in out.stdout + out.stderr
    assert (built[0].stat().st_mtime_ns, digest(built[0])) == before
    wheels = list((work / "dist").glob("raypc-*.whl"))
    assert len(wheels) == 1, wheels
    assert "-cp3" in wheels[0].name and "linux" in wheels[0].name  # a compiled module: tagged, not py3-none-any
    # setuptools worked under the build tree, not in the source tree
    assert not list((SOURCE / "src" / "python").glob("*.egg-info"))

    env_dir = work / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(env_dir)], check=True)
    python = env_dir / "bin" / "python"
    # Debian's pip, seen through the system site-packages; nothing from the network.
    out = subprocess.run([str(python), "-m", "pip", "install", "--no-deps", "--no-index", str(wheels[0])],
                         env=CLEAN_ENV, capture_output=True, text=True, cwd=work)
    assert out.returncode == 0, out.stderr
    return python


def in_venv(python, code, *args, check=True):
    """Runs Python code in the venv from outside the source tree; returns the completed process."""
    out = subprocess.run([str(python), "-c", textwrap.dedent(code), *map(str, args)], env=CLEAN_ENV,
                         capture_output=True, text=True, cwd=python.parents[2], timeout=600)
    if check:
        assert out.returncode == 0, out.stderr
    return out


def test_imports_from_the_venv_with_its_metadata(venv):
    out = in_venv(venv, """
        import importlib.metadata as md, json, raypc
        eps = [(e.name, e.value) for e in md.entry_points(group="xarray.backends") if e.dist.name == "raypc"]
        files = [str(f) for f in md.files("raypc")]
        print(json.dumps([raypc.__file__, raypc.__version__, md.version("raypc"), eps, files,
                          md.metadata("raypc")["Requires-Python"], md.requires("raypc")]))
        """)
    where, version, metadata_version, eps, files, requires_python, requires = json.loads(out.stdout)
    assert Path(where).is_relative_to(venv.parents[1]) and not Path(where).is_relative_to(SOURCE)
    assert version == metadata_version
    # the one version: project(RayPC VERSION …), also `raypc --version`
    assert subprocess.run([RAYPC_EXE, "--version"], capture_output=True, text=True).stdout.split() == ["raypc", version]
    assert eps == [["raypc", "raypc.xarray_backend:RaypcBackendEntrypoint"]]
    assert "raypc/py.typed" in files and "raypc/web/index.html" in files and "raypc/examples/titles.tsv" in files
    assert any(f.startswith("raypc/_raypc") and f.endswith(".so") for f in files)
    assert requires_python and "numpy" in requires and any(r.startswith("xarray") and "extra" in r for r in requires)


def as_executable(*args):
    """The raypc executable named `raypc` in its help, as `python -m raypc` names it."""
    return subprocess.run(["raypc", *map(str, args)], executable=RAYPC_EXE, capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("args", [["--help"], ["--version"], ["info", "--help"], ["info", "{dataset}"],
                                  ["info", "{dataset}", "--json"], ["info", "/nonexistent/dataset"],
                                  ["probe", "--no-such-option"], []])
def test_python_m_raypc_is_the_executable(venv, contest, args):
    args = [a.format(dataset=contest.path) for a in args]
    module = subprocess.run([str(venv), "-m", "raypc", *args], env=CLEAN_ENV, capture_output=True, text=True,
                            cwd=venv.parents[2], timeout=600)
    exe = as_executable(*args)
    assert (module.returncode, module.stdout, module.stderr) == (exe.returncode, exe.stdout, exe.stderr)
    assert module.stdout or module.stderr  # each case says something


def test_show_serves_the_ui_and_the_examples_inside_the_package(venv, contest):
    # Mark the installed copies: the page and the preset must come from the package, not from the
    # source tree that the build tree's lookup would find.
    package = Path(in_venv(venv, "import raypc, os; print(os.path.dirname(raypc.__file__))").stdout.strip())
    index = package / "web" / "index.html"
    index.write_text(index.read_text() + "<!-- served from the installed package -->\n")
    (package / "examples" / "installed-only.json").write_text(json.dumps({"step": 1}))
    out = in_venv(venv, """
        import json, sys, urllib.request, raypc
        view = raypc.show(sys.argv[1])
        page = urllib.request.urlopen(view.url, timeout=10).read().decode()
        presets = json.loads(urllib.request.urlopen(view.url.rstrip("/") + "/api/presets", timeout=10).read())
        view.close()
        print(json.dumps(["served from the installed package" in page, "<script" in page,
                          [p["name"] for p in presets]]))
        """, contest.path)
    marked, has_script, names = json.loads(out.stdout)
    assert marked and has_script
    assert "installed-only" in names and "task1-slabs-660km" in names


def test_the_module_tests_pass_on_the_installed_package(venv):
    # The installed raypc is imported first, so the tests (and their conftest) use it.
    out = in_venv(venv, """
        import os, sys, pytest, raypc
        assert raypc.__file__.startswith(sys.prefix), raypc.__file__
        sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", sys.argv[1]]))
        """, SOURCE / "tests" / "python" / "test_dataset.py", check=False)
    assert out.returncode == 0, out.stdout[-4000:] + out.stderr[-4000:]
    assert " passed" in out.stdout and "failed" not in out.stdout


def test_python_m_raypc_serve_stops_on_ctrl_c(venv, contest):
    import signal
    import urllib.request

    server = subprocess.Popen([str(venv), "-m", "raypc", "serve", str(contest.path), "--port", "0"], env=CLEAN_ENV,
                              stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              cwd=venv.parents[2])
    try:
        # The log (on stdout), then "raypc: serving URL" once the port is bound.
        lines = []
        while not (lines and lines[-1].startswith("raypc: serving ")):
            line = server.stdout.readline()
            assert line, "".join(lines)  # ended before serving
            lines.append(line)
        url = lines[-1].split()[-1]
        # the UI and the presets of the installed package, not of the source tree
        package = venv.parents[1] / "lib"
        assert any("serving the UI from" in line and str(package) in line for line in lines), lines
        assert any("presets from" in line and str(package) in line for line in lines), lines
        # Once it answers, the server runs, and it stops on SIGINT by its own handler.
        with urllib.request.urlopen(url + "api/info", timeout=10) as answer:
            assert answer.status == 200
        server.send_signal(signal.SIGINT)
        assert server.wait(timeout=20) == 0
        assert "signal 2: stopping" in server.stdout.read()
    finally:
        if server.poll() is None:
            server.kill()
            server.wait()


def test_main_in_process_gives_python_its_ctrl_c_back(contest):
    """_raypc.main called from Python (the build tree's module): `serve` stops on SIGINT by its own
    handler, and afterwards Ctrl-C is Python's KeyboardInterrupt again (a handler left at the
    default would end this process instead)."""
    import signal
    import threading
    import urllib.request

    import raypc

    with pytest.raises(raypc.Error, match="argv is empty"):
        raypc._raypc.main([])
    import socket

    with socket.socket() as probe:  # a port free a moment ago (serve fails loudly if it is taken since)
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]

    def interrupt_once_serving():
        for _ in range(200):
            try:
                urllib.request.urlopen(f"http://127.0.0.1:{port}/api/info", timeout=1).close()
                break
            except OSError:
                time.sleep(0.05)
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=interrupt_once_serving, daemon=True).start()
    assert raypc._raypc.main(["raypc", "serve", str(contest.path), "--port", str(port)]) == 0
    with pytest.raises(KeyboardInterrupt):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(1)
