"""One version, one home: pyscripts/trueaniso/VERSION. The Python package, the compiled engines
(CMake reads the file) and a study's metadata.json all say the same, and the file is not part of
the code version (the hash of what makes the numbers)."""
import json
import os
import re

from conftest import REPO, run_script

VERSION_FILE = os.path.join(REPO, "pyscripts", "trueaniso", "VERSION")


def the_version():
    with open(VERSION_FILE) as f:
        text = f.read()
    assert re.fullmatch(r"\d+\.\d+\.\d+\n", text), "VERSION holds one line MAJOR.MINOR.PATCH: %r" % text
    return text.strip()


def test_package_and_engines_say_the_version_file():
    import trueaniso
    from trueaniso import engines
    assert trueaniso.__version__ == the_version()
    assert engines.version() == the_version()


def test_cmake_reads_the_version_file():
    """The CMake project's version is the file's, not a number written twice."""
    with open(os.path.join(REPO, "CMakeLists.txt")) as f:
        cmake = f.read()
    assert re.search(r"project\(trueaniso VERSION \$\{TRUEANISO_VERSION\}", cmake)
    assert "pyscripts/trueaniso/VERSION TRUEANISO_VERSION" in cmake


def test_changelog_lists_the_version():
    with open(os.path.join(REPO, "CHANGELOG.md")) as f:
        headings = [ln for ln in f if ln.startswith("## ")]
    assert headings[0].strip() == "## Unreleased"
    assert any(h.startswith("## %s " % the_version()) for h in headings)


def test_version_file_is_outside_the_code_version():
    """The engines' hash counts .cpp .hpp .h .txt .cmake under engines/ and the package's its .py
    files: a release number on the same code leaves the code version alone."""
    from trueaniso import provenance
    assert not VERSION_FILE.endswith(provenance.ENGINE_SUFFIXES + (".py",))
    assert not os.path.join("engines", "core", "Version.hpp.in").endswith(provenance.ENGINE_SUFFIXES)


def test_study_metadata_records_the_version(specimen_100, tmp_path):
    out = tmp_path / "study"
    proc = run_script("run_states.py", "--specimen", specimen_100, "--states", "0:100e3", "--probes", "z",
                      "--out", out)
    assert proc.returncode == 0, proc.stderr
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["versions"]["trueaniso"] == the_version()
