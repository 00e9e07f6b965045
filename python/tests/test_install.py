"""The package installs offline and finds its library: `pip install
--no-build-isolation --no-index` of a copy of python/ into a virtual
environment of /usr/bin/python3 (the library copied into the package), and
`cmake --install` to a prefix with PYTHONPATH (the library found beside the
package); each then meshes a model from another directory.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import os
import shutil
import subprocess
import sys

import pytest

from conftest import SCREW, SOURCE

BUILD = os.environ["HOCAD_BUILD_DIR"]
CHECK = ("import hocad, sys; print(hocad.LIBRARY_PATH); "
         "r = hocad.mesh_file(sys.argv[1], order=1); print(r['elements'])")


def clean_env(**extra):
    """The environment without the test's own library and package paths."""
    env = {k: v for k, v in os.environ.items() if k not in ("HOCAD_LIBRARY", "PYTHONPATH")}
    env.update(extra)
    return env


def run_check(python, cwd, env):
    out = subprocess.run([python, "-c", CHECK, SCREW], cwd=cwd, env=env, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    path, elements = out.stdout.split()
    assert int(elements) > 100
    return path


def test_pip_install_offline(tmp_path):
    src = tmp_path / "src"
    shutil.copytree(os.path.join(SOURCE, "python"), src,
                    ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__", "tests"))
    venv = tmp_path / "venv"
    # --without-pip: the venv uses Debian's pip (python3-pip) from the system site
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip",
                    str(venv)], check=True)
    python = str(venv / "bin" / "python")
    env = clean_env(HOCAD_LIBRARY=os.environ["HOCAD_LIBRARY"], PIP_NO_INPUT="1")
    out = subprocess.run([python, "-m", "pip", "install", "--no-build-isolation", "--no-index",
                          str(src)], env=env, capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stdout + out.stderr
    path = run_check(python, tmp_path, clean_env())
    assert path.startswith(str(venv)) and os.path.basename(path) == "libhocad.so"


def test_cmake_install_pythonpath(tmp_path):
    prefix = tmp_path / "prefix"
    subprocess.run(["cmake", "--install", BUILD, "--prefix", str(prefix)], check=True,
                   capture_output=True)
    site = prefix / "lib" / "python3" / "dist-packages"
    assert (site / "hocad" / "__init__.py").exists()
    path = run_check(sys.executable, tmp_path, clean_env(PYTHONPATH=str(site)))
    assert os.path.dirname(path) == str(prefix / "lib")
    assert os.path.basename(path).startswith("libhocad.so.")
    # the example runs on the installed package
    out = subprocess.run([sys.executable, os.path.join(SOURCE, "python", "examples",
                                                       "mesh_report.py"), SCREW, "ex.msh"],
                         cwd=tmp_path, env=clean_env(PYTHONPATH=str(site)), capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "optimized" in out.stdout and (tmp_path / "ex.msh").exists()


def test_missing_library_is_a_clear_error(tmp_path):
    env = clean_env(HOCAD_LIBRARY=str(tmp_path / "nowhere.so"),
                    PYTHONPATH=os.path.join(SOURCE, "python"))
    out = subprocess.run([sys.executable, "-c", "import hocad"], env=env, capture_output=True,
                         text=True)
    assert out.returncode != 0
    assert "ImportError: hocad: cannot load libhocad.so" in out.stderr
    assert "nowhere.so (no such file)" in out.stderr
