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
    (tmp_path / "repo" / "cmake").mkdir(parents=True, exist_ok=True)
    shutil.copy(os.path.join(REPO, "cmake", "yade_source.sh"), tmp_path / "repo" / "cmake")
    env = {k: v for k, v in os.environ.items() if k != "TRUEANISO_YADE_SOURCE"}
    if source is not None:
        env["TRUEANISO_YADE_SOURCE"] = str(source)
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


def test_an_unpacked_tree_is_remembered_for_a_setup_without_the_variable(tmp_path):
    """A setup without TRUEANISO_YADE_SOURCE after one that named an unpacked tree found no source
    and removed the plugin built from it (cmake/yade_plugin.sh); the tree's path is remembered."""
    tree = tmp_path / "yade-2023.02a"
    (tree / "core").mkdir(parents=True)
    (tree / "core" / "Scene.hpp").write_text("")
    (tree / "RELEASE").write_text("2023.02a\n")
    first = _run(tmp_path, tree)
    assert first.returncode == 0 and first.stdout.strip() == str(tree), first.stderr
    again = _run(tmp_path, None)
    assert again.returncode == 0 and again.stdout.strip() == str(tree), again.stderr
