"""cmake/yade_source.sh, where the YADE plugin's source comes from: TRUEANISO_YADE_SOURCE names the
orig tarball, the directory that holds it (as ../shared/deps beside a clone), or an unpacked tree.
Run on a copy of the script in a scratch directory, with a stand-in tarball: its checksum is
refused, which shows which file the script took (no unpacking, no network)."""
import os
import shutil
import subprocess

from conftest import REPO

TARBALL = "yade_2023.02a.orig.tar.bz2"


def _run(tmp_path, source):
    (tmp_path / "repo" / "cmake").mkdir(parents=True)
    shutil.copy(os.path.join(REPO, "cmake", "yade_source.sh"), tmp_path / "repo" / "cmake")
    env = dict(os.environ, TRUEANISO_YADE_SOURCE=str(source))
    return subprocess.run(["bash", str(tmp_path / "repo" / "cmake" / "yade_source.sh")], capture_output=True,
                          text=True, env=env, timeout=60)


def test_the_directory_that_holds_the_tarball_names_the_tarball(tmp_path):
    deps = tmp_path / "deps"
    deps.mkdir()
    (deps / TARBALL).write_bytes(b"not YADE")
    proc = _run(tmp_path, deps)
    assert proc.returncode == 1 and proc.stdout == ""
    assert proc.stderr.startswith("TRUEANISO_YADE_SOURCE=%s has sha256 " % (deps / TARBALL)), proc.stderr
    assert not (tmp_path / "repo" / "build" / "yade-source").exists()


def test_a_directory_with_neither_is_refused_naming_both(tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    proc = _run(tmp_path, empty)
    assert proc.returncode == 1
    assert "is not a YADE 2023.02a source tree" in proc.stderr and "holds no %s" % TARBALL in proc.stderr
