"""Builds the `lambert` Python package with the project's CMake (see pyproject.toml).

`pip install .` configures a Release build of the extension alone (no tests, benchmarks or
MPI) in build-pip/, builds the `lambert_python` target, and packages it with the pure-Python
modules of python/lambert/ and the built-in Cornell box (data/cornell_box/, found by the
package through LAMBERT_DATA_DIR). The version is the one in CMakeLists.txt's project().
"""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
BUILD = ROOT / "build-pip"


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text()
    return re.search(r"project\(lambert VERSION ([0-9.]+)", text).group(1)


class CMakeBuild(build_ext):
    """Builds _lambert with CMake and copies it where setuptools expects the extension."""

    def build_extension(self, ext):
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(BUILD), "-DCMAKE_BUILD_TYPE=Release",
                        "-DLAMBERT_BUILD_TESTS=OFF", "-DLAMBERT_BUILD_BENCH=OFF",
                        "-DLAMBERT_MPI=OFF", f"-DPython3_EXECUTABLE={sys.executable}"],
                       check=True)
        subprocess.run(["cmake", "--build", str(BUILD), "--target", "lambert_python",
                        "-j", str(os.cpu_count() or 1)], check=True)
        built = sorted((BUILD / "python" / "lambert").glob("_lambert*.so"))
        if not built:
            sys.exit("setup.py: CMake built no _lambert extension in " + str(BUILD))
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[-1], target)


class BuildPyWithData(build_py):
    """Adds the built-in Cornell box to the package (lambert/data/cornell_box/)."""

    def run(self):
        super().run()
        shutil.copytree(ROOT / "data" / "cornell_box",
                        Path(self.build_lib) / "lambert" / "data" / "cornell_box",
                        dirs_exist_ok=True)


setup(
    version=project_version(),
    packages=["lambert"],
    package_dir={"lambert": "python/lambert"},
    ext_modules=[Extension("lambert._lambert", sources=[])],
    cmdclass={"build_ext": CMakeBuild, "build_py": BuildPyWithData},
    zip_safe=False,
)
