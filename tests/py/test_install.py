"""`cmake --install` gives a working installation: the Python module with the trueaniso and analysis
packages found by Debian's python3 from anywhere, the scripts runnable, and the engines library
with self-contained headers for a C++ user."""
import os
import subprocess
import sys

import pytest

from conftest import REPO

BUILD = os.environ.get("TRUEANISO_BUILD", os.path.join(REPO, "build"))


@pytest.fixture(scope="module")
def prefix(tmp_path_factory):
    root = tmp_path_factory.mktemp("install")
    subprocess.run(["cmake", "--install", BUILD, "--prefix", str(root)], check=True, capture_output=True)
    return root


def _env(prefix):
    env = {k: v for k, v in os.environ.items() if k not in ("TRUEANISO_BUILD", "PYTHONPATH")}
    env["PYTHONPATH"] = str(prefix / "lib" / ("python%d.%d" % sys.version_info[:2]) / "dist-packages")
    return env


def test_python_module_and_scripts_run_from_the_installation(prefix, tmp_path):
    probe = ("import trueaniso, analysis.figures; from trueaniso import provenance; e = trueaniso.engines; "
             "print(e.__file__); print(trueaniso.__file__); print(e.PROBE_FRICTION); print(provenance.code_version())")
    out = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=_env(prefix), capture_output=True,
                         text=True, check=True).stdout.split()
    assert out[0].startswith(str(prefix)) and out[1].startswith(str(prefix))  # not the build tree
    # the level the module was built for is installed beside it (read before the module loads)
    assert (prefix / os.path.dirname(os.path.relpath(out[0], prefix)) / "_trueaniso.arch").is_file()
    assert float(out[2]) == 1e23
    # the same sources installed are the same code: a study can be continued from the installation
    from trueaniso import provenance
    assert out[3] == provenance.code_version()
    script = prefix / "share" / "trueaniso" / "scripts" / "run_states.py"
    help_text = subprocess.run([sys.executable, str(script), "--help"], cwd=tmp_path, env=_env(prefix),
                               capture_output=True, text=True, check=True).stdout
    assert "--specimen" in help_text


def test_cpp_user_builds_against_installed_headers_and_library(prefix, tmp_path):
    src = tmp_path / "user.cpp"
    src.write_text('''
#include "contact/HertzMindlin.hpp"
#include "core/Scene.hpp"
#include "dynamics/ContactRefresh.hpp"
#include "measure/Stress.hpp"
#include <cstdio>
int main() {
  trueaniso::Scene s;
  s.cell.setBox(trueaniso::Vec3::Constant(1e-3));
  s.addSphere(trueaniso::Vec3(0.4e-3, 0.5e-3, 0.5e-3), 1e-4);
  s.addSphere(trueaniso::Vec3(0.5999e-3, 0.5e-3, 0.5e-3), 1e-4);
  trueaniso::refreshContacts(s);
  std::printf("%.6e\\n", s.contacts.normalForce[0]);
}
''')
    exe = tmp_path / "user"
    subprocess.run(["g++", "-std=c++17", "-O1", "-fopenmp", "-I", str(prefix / "include" / "trueaniso"),
                    "-I", "/usr/include/eigen3", str(src), str(prefix / "lib" / "libtrueaniso_engines.a"),
                    "-lcholmod", "-lmpfr", "-lgmp", "-o", str(exe)],  # MPFR, GMP: CGAL's (clump templates)
                   check=True, capture_output=True)
    N = float(subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout)
    # Hertz of two r = 0.1 mm spheres overlapping by 0.1 um: (4/3) E* sqrt(r/2) delta^1.5, E* = G/(1-nu)
    estar = 18e9 / (1 - 0.15)
    assert N == pytest.approx(4 / 3 * estar * (0.5e-4) ** 0.5 * (1e-7) ** 1.5, rel=1e-6)
