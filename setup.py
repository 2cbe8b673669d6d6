"""The raypc wheel from the project's CMake build (pyproject.toml holds the metadata).

Nothing is compiled here: build_ext runs the CMake build of the compiled module ``_raypc`` in the
existing build tree (``build/``, or ``$RAYPC_BUILD_DIR``; configured as scripts/build.sh does when
absent), so that after the README's build ``pip install --no-build-isolation .`` only copies. It
builds the browser UI (scripts/build-web.sh) only when its output, web/dist, is absent. The wheel
holds the package's .py files, ``_raypc``, the UI's files (raypc/web) and the example states
(raypc/examples), which ``raypc.show()`` serves from there. setuptools' own files go under the build
tree too (``<build>/python-wheel``), so the source tree stays clean."""
import os
import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
BUILD = Path(os.environ.get("RAYPC_BUILD_DIR") or ROOT / "build").resolve()
WHEEL_WORK = BUILD / "python-wheel"


def project_version() -> str:
    """The one version: project(RayPC VERSION x.y.z) in CMakeLists.txt, which the compiled module
    also reports (raypc.__version__, `raypc --version`)."""
    text = (ROOT / "CMakeLists.txt").read_text()
    found = re.search(r"project\(\s*RayPC\s+VERSION\s+([0-9][0-9.]*)", text)
    if not found:
        sys.exit("setup.py: CMakeLists.txt has no `project(RayPC VERSION x.y.z)`, which gives the package its version")
    return found.group(1)


def run(command: list) -> None:
    print("setup.py:", " ".join(str(c) for c in command), flush=True)
    subprocess.run([str(c) for c in command], check=True)


class CMakeBuild(build_ext):
    """Builds _raypc with CMake and packs it with the UI's files and the example states."""

    def build_extension(self, ext: Extension) -> None:
        if self.inplace:
            sys.exit("setup.py: no in-place (editable) install; from the build tree use PYTHONPATH=build/python "
                     "(docs/python.md), or `pip install --no-build-isolation .`")
        if not (BUILD / "CMakeCache.txt").is_file():
            launcher = ["-DCMAKE_C_COMPILER_LAUNCHER=ccache", "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"] \
                if shutil.which("ccache") else []
            # The interpreter behind a venv: the module is built for this Python's version.
            python = getattr(sys, "_base_executable", None) or sys.executable
            run(["cmake", "-S", ROOT, "-B", BUILD, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                 "-DCMAKE_UNITY_BUILD=ON", f"-DPYTHON_EXECUTABLE={python}", *launcher])
        # Up to date after the README's build: ninja says "no work to do" and nothing is compiled.
        run(["cmake", "--build", BUILD, "--target", "_raypc"])
        self.copy_module(ext)
        package = Path(self.build_lib) / "raypc"
        self.copy_ui(package / "web")
        self.copy_examples(package / "examples")

    def copy_module(self, ext: Extension) -> None:
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        built = BUILD / "python" / "raypc" / f"_raypc{suffix}"
        if not built.is_file():
            found = sorted(p.name for p in (BUILD / "python" / "raypc").glob("_raypc*"))
            sys.exit(f"setup.py: {built} not found ({', '.join(found) or 'no _raypc'} there): the build tree "
                     f"{BUILD} is for another Python than this one ({sys.executable}, {suffix}); build with "
                     f"this Python's pip (/usr/bin/python3 -m pip), or another RAYPC_BUILD_DIR")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, target)

    def copy_ui(self, target: Path) -> None:
        dist = ROOT / "web" / "dist"
        if not (dist / "index.html").is_file():
            # The UI's types are generated from the schemas the executable writes (web/CMakeLists.txt).
            run(["cmake", "--build", BUILD, "--target", "web_state_schema"])
            run([ROOT / "scripts" / "build-web.sh"])
        if target.exists():
            shutil.rmtree(target)
        shutil.copytree(dist, target)

    def copy_examples(self, target: Path) -> None:
        # The example states and their titles (what GET /api/presets lists), not the notebook.
        if target.exists():
            shutil.rmtree(target)
        target.mkdir(parents=True)
        for state in sorted((ROOT / "examples").iterdir()):
            if state.suffix == ".json" or state.name == "titles.tsv":
                shutil.copy2(state, target / state.name)


WHEEL_WORK.mkdir(parents=True, exist_ok=True)
setup(
    version=project_version(),
    # Names the compiled module so that the wheel is tagged for this Python and platform; its
    # sources are CMake's (CMakeBuild).
    ext_modules=[Extension("raypc._raypc", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": str(WHEEL_WORK)}, "egg_info": {"egg_base": str(WHEEL_WORK)}},
)
