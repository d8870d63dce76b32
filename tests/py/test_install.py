"""`cmake --install` gives a working installation: the Python module with the trueaniso package
(trueaniso.analysis in it) found by Debian's python3 from anywhere, the scripts runnable, and the
engines library with self-contained headers for a C++ user. And ./setup.sh links a checkout's
package for python3 and yade-double (cmake/link_package.sh)."""
import json
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
    probe = ("import trueaniso, trueaniso.analysis.figures; from trueaniso import provenance; e = trueaniso.engines; "
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


def test_setup_links_the_checkout_for_python3_and_yade(tmp_path):
    """cmake/link_package.sh writes a .pth naming this checkout's pyscripts/ into a site directory
    (here one of the test's own, TRUEANISO_SITE), says so once, and then both interpreters import
    trueaniso.analysis from this checkout in a folder of their own, with no PYTHONPATH."""
    site = tmp_path / "site"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["TRUEANISO_SITE"] = str(site)
    link = os.path.join(REPO, "cmake", "link_package.sh")
    first = subprocess.run([link], env=env, capture_output=True, text=True, check=True)
    assert "import trueaniso from %s" % os.path.join(REPO, "pyscripts") in first.stdout
    assert (site / "trueaniso.pth").read_text().strip() == os.path.join(REPO, "pyscripts")
    again = subprocess.run([link], env=env, capture_output=True, text=True, check=True)
    assert again.stdout == again.stderr == ""  # nothing changed, nothing said
    (site / "trueaniso.pth").write_text("/elsewhere/pyscripts\n")
    moved = subprocess.run([link], env=env, capture_output=True, text=True, check=True)
    assert "now import trueaniso from" in moved.stdout and "(was /elsewhere/pyscripts)" in moved.stdout
    # the machine's own site directory may hold a trueaniso.pth of another checkout (the one set up
    # last, on a shared machine): it is left out, so that what is read is the test's own link
    probe = ("import site, sys; sys.path[:] = [p for p in sys.path if not p.endswith('/pyscripts')]; "
             "site.addsitedir(%r); import trueaniso.analysis.report as r; print(r.__file__)" % str(site))
    out = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, env=env, capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == os.path.join(REPO, "pyscripts", "trueaniso", "analysis", "report.py")
    script = tmp_path / "in_yade.py"
    script.write_text(probe.replace("print(r.__file__)", "import json; json.dump(r.__file__, open(sys.argv[-1], 'w'))")
                      + "\n")
    proc = subprocess.run(["yade-double", "-n", "-x", str(script), str(tmp_path / "out.json")], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert json.loads((tmp_path / "out.json").read_text()) == out
