"""Build step of the hocad Python package (pyproject.toml holds the rest):
put libhocad.so inside the package, so an installed package needs no
build tree. The library is, in order: the file HOCAD_LIBRARY names; the
checkout's build/libhocad.so (cmake --build build); else one built here
with CMake (the shared library only, in python/build/libhocad).
SPDX-License-Identifier: GPL-2.0-or-later
"""
import os
import shutil
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.dist import Distribution

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


def find_library():
    env = os.environ.get("HOCAD_LIBRARY")
    if env:
        if not os.path.isfile(env):
            raise SystemExit("HOCAD_LIBRARY=%s: no such file" % env)
        return env
    built = os.path.join(REPO, "build", "libhocad.so")
    if os.path.isfile(built):
        return built
    if not os.path.isfile(os.path.join(REPO, "CMakeLists.txt")):
        raise SystemExit("no libhocad.so: set HOCAD_LIBRARY, or build from a checkout")
    out = os.path.join(HERE, "build", "libhocad")
    subprocess.check_call(["cmake", "-S", REPO, "-B", out, "-DCMAKE_BUILD_TYPE=Release",
                           "-DHOCAD_TESTS=OFF"])
    subprocess.check_call(["cmake", "--build", out, "--target", "hocad_shared", "-j2"])
    return os.path.join(out, "libhocad.so")


class BuildWithLibrary(build_py):
    """build_py that also copies libhocad.so into the package."""

    def run(self):
        super().run()
        src = os.path.realpath(find_library())
        dst = os.path.join(self.build_lib, "hocad", "libhocad.so")
        self.announce("copying %s -> %s" % (src, dst), level=2)
        shutil.copyfile(src, dst)
        os.chmod(dst, 0o755)


class BinaryDistribution(Distribution):
    """The wheel holds a compiled library: tag it for this platform."""

    def has_ext_modules(self):
        return True


setup(cmdclass={"build_py": BuildWithLibrary}, distclass=BinaryDistribution)
