"""pip install --no-build-isolation .  installs the Python package `cdp` for the interpreter
running pip, its compiled module cdp._cdp built by the project's CMake (python/README.md,
"Install with pip").

The module is the CMake target cdp_python; this file only picks a build directory, builds that
target there and packages python/cdp/*.py, *.pyi, py.typed with the module and the _version.py
CMake writes. The build directory, in this order:

  CDP_BUILD_DIR=DIR  that directory: configured already (for this interpreter, this source tree,
                     with CDP_BUILD_PYTHON=ON), or configured here if it has no CMakeCache.txt;
  ./build            the project's own build (`make build`), when it was configured so;
  ./build-pip/TAG    otherwise: configured here (Release, no tests, benchmarks or programs) and
                     kept, so that installing again only rebuilds what changed.

No lock is taken: a build directory that another `cmake --build` is using at the same time must
be serialised by the caller (flock LOCKFILE pip install ...). Editable installs are refused: the
build tree (PYTHONPATH=build/python) is the development layout.
"""
import atexit
import hashlib
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE_DIR = pathlib.Path(__file__).resolve().parent
PACKAGE_DIR = SOURCE_DIR / "python" / "cdp"


def project_version():
    """The one version of the project: project(cdp VERSION x.y.z) in CMakeLists.txt, which CMake
    also writes into cdp/_version.py."""
    text = (SOURCE_DIR / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\(\s*cdp\s+VERSION\s+([0-9][0-9.]*)", text)
    if not match:
        sys.exit("setup.py: no `project(cdp VERSION x.y.z ...)` in CMakeLists.txt")
    return match.group(1)


# What decides whether a module imports into an interpreter: the same installation (a virtual
# environment shares its base's), version and extension ABI. Asked of the interpreter CMake
# cached, so a build configured for /usr/bin/python3 serves a venv made from it, and one made for
# another Python (a pyenv 3.11 has the same EXT_SUFFIX) does not.
_FINGERPRINT = ("import json, os, sys, sysconfig; print(json.dumps([os.path.realpath(sys.base_prefix), sys.version, "
                "sysconfig.get_config_var('EXT_SUFFIX')]))")


def this_interpreter():
    return [os.path.realpath(sys.base_prefix), sys.version, sysconfig.get_config_var("EXT_SUFFIX")]


def base_interpreter():
    """The interpreter a fresh configuration is given: a venv's base, so that the build directory
    outlives the venv (its module serves every venv of that base)."""
    base = getattr(sys, "_base_executable", None)
    return base if base and os.path.exists(base) else sys.executable


def read_cache(build_dir):
    cache = {}
    path = build_dir / "CMakeCache.txt"
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        match = re.match(r"([A-Za-z_0-9]+):[A-Z]+=(.*)$", line)
        if match:
            cache[match.group(1)] = match.group(2)
    return cache


def unusable(build_dir):
    """Why a configured build directory cannot build the module for this interpreter, or None."""
    cache = read_cache(build_dir)
    home = cache.get("CMAKE_HOME_DIRECTORY", "")
    if not home or pathlib.Path(home).resolve() != SOURCE_DIR:
        return f"it was configured for the source tree {home or '(unknown)'}, not {SOURCE_DIR}"
    if cache.get("CDP_BUILD_PYTHON", "").upper() not in ("ON", "TRUE", "1", "YES"):
        return "CDP_BUILD_PYTHON is OFF there (a sanitizer build, or pybind11 was not found)"
    python = cache.get("Python_EXECUTABLE", "")
    try:
        theirs = json.loads(subprocess.run([python, "-c", _FINGERPRINT], check=True, capture_output=True,
                                           text=True).stdout)
    except (OSError, subprocess.CalledProcessError, ValueError):
        return f"its Python_EXECUTABLE {python or '(unset)'} does not run"
    if theirs != this_interpreter():
        return f"its Python_EXECUTABLE {python} is not {sys.executable} ({theirs[1].split()[0]}, {theirs[0]})"
    return None


def configure(build_dir):
    python = base_interpreter()
    args = ["cmake", "-S", str(SOURCE_DIR), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython_EXECUTABLE={python}", f"-DPYTHON_EXECUTABLE={python}", "-DCDP_BUILD_PYTHON=ON",
            "-DCDP_BUILD_TESTS=OFF", "-DCDP_BUILD_BENCHMARKS=OFF", "-DCDP_BUILD_APPS=OFF"]
    try:
        import pybind11  # in an isolated build (PyPI's pybind11), CMake would not find it alone
        cmake_dir = pybind11.get_cmake_dir()
        if os.path.exists(os.path.join(cmake_dir, "pybind11Config.cmake")):
            args.append(f"-Dpybind11_DIR={cmake_dir}")
    except ImportError:
        pass  # CMake's own search (Debian's pybind11-dev), or its message naming what is missing
    print("setup.py: configuring", build_dir, flush=True)
    subprocess.run(args, check=True)


def build_directory():
    explicit = os.environ.get("CDP_BUILD_DIR")
    if explicit:
        build_dir = pathlib.Path(explicit).resolve()
        if not (build_dir / "CMakeCache.txt").exists():
            configure(build_dir)
        elif (reason := unusable(build_dir)):
            sys.exit(f"setup.py: CDP_BUILD_DIR={build_dir} cannot build cdp for {sys.executable}: {reason}")
        return build_dir
    default = SOURCE_DIR / "build"
    if (default / "CMakeCache.txt").exists():
        reason = unusable(default)
        if reason is None:
            return default
        print(f"setup.py: not reusing {default}: {reason}", flush=True)
    tag = sys.implementation.cache_tag + "-" + hashlib.sha1(json.dumps(this_interpreter()).encode()).hexdigest()[:8]
    build_dir = SOURCE_DIR / "build-pip" / tag
    if not (build_dir / "CMakeCache.txt").exists() or unusable(build_dir):
        configure(build_dir)
    return build_dir


class CMakeBuild(build_ext):
    """Builds cdp._cdp with the project's CMake (target cdp_python) and copies it, with the
    _version.py that CMake writes, into the wheel's tree."""

    def run(self):
        if self.inplace:
            sys.exit("setup.py: editable installs are not supported; for development import the build tree "
                     "(cmake --build build --target cdp_python; PYTHONPATH=build/python)")
        super().run()

    def build_extension(self, ext):
        build_dir = build_directory()
        command = ["cmake", "--build", str(build_dir), "--target", "cdp_python"]
        if "CMAKE_BUILD_PARALLEL_LEVEL" not in os.environ:
            command += ["-j", str(os.cpu_count() or 1)]
        print("setup.py:", " ".join(command), flush=True)
        subprocess.run(command, check=True)
        built = build_dir / "python" / "cdp"
        module = built / ("_cdp" + sysconfig.get_config_var("EXT_SUFFIX"))
        if not module.exists():
            found = ", ".join(sorted(p.name for p in built.glob("_cdp*"))) or "nothing"
            sys.exit(f"setup.py: {module} was not built (found {found} in {built})")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(module, target)
        shutil.copyfile(built / "_version.py", target.parent / "_version.py")


# setuptools' scratch files (build/lib.*, build/bdist.*, cdp.egg-info) would land in the clone,
# build/ being the CMake build directory: they go to a temporary directory instead (pip builds
# in the source tree, and runs each of its steps in a process of its own).
_scratch = tempfile.mkdtemp(prefix="cdp-setuptools-")
atexit.register(shutil.rmtree, _scratch, ignore_errors=True)

setup(
    name="cdp",
    version=project_version(),
    description="Curvature-dependent polygonization of implicit surfaces: fields, an adaptive polygonizer, "
                "Marching Cubes and Tetrahedra, curvature and evaluation on numpy arrays",
    long_description=(SOURCE_DIR / "python" / "README.md").read_text(encoding="utf-8"),
    long_description_content_type="text/markdown",
    python_requires=">=3.9",
    install_requires=["numpy"],
    packages=["cdp"],
    package_dir={"": "python"},
    package_data={"cdp": ["*.pyi", "py.typed"]},
    ext_modules=[Extension("cdp._cdp", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    zip_safe=False,
    options={"build": {"build_base": os.path.join(_scratch, "build")},
             "egg_info": {"egg_base": _scratch}},
)
