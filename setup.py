"""pip install --no-build-isolation . : builds the pybind11 module with the project's CMake build."""

import glob
import os
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = os.path.dirname(os.path.abspath(__file__))


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        subprocess.check_call(
            [
                "cmake", "-S", SOURCE, "-B", build, "-DCMAKE_BUILD_TYPE=Release",
                f"-DPython_EXECUTABLE={sys.executable}", "-DNOVAPHY_BUILD_TESTS=OFF",
            ]
        )
        subprocess.check_call(["cmake", "--build", build, "--target", "_novaphy", "-j", str(os.cpu_count() or 1)])
        (built,) = glob.glob(os.path.join(build, "python", "novaphy", "_novaphy*.so"))
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copy(built, target)


setup(
    packages=["novaphy"],
    package_dir={"novaphy": "bindings/python/novaphy"},
    package_data={"novaphy": ["*.pyi", "py.typed"]},
    ext_modules=[CMakeExtension("novaphy._novaphy")],
    cmdclass={"build_ext": CMakeBuild},
    zip_safe=False,
)
