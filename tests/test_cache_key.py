"""The kernel cache key cannot go stale: it hashes every Python file of the package, so an
edit anywhere in jetnh/ (a comment, a constant of a principle), a moved file or a new one
gives new keys, and a warm cache never serves kernels derived by older sources."""

import shutil
from pathlib import Path

import pytest

import jetnh
from jetnh.numeric.codegen import KernelSpec, spec
from jetnh.numeric.codegen.spec import source_hash

ROOT = Path(jetnh.__file__).resolve().parent


@pytest.fixture
def package(tmp_path):
    """A copy of the package's sources (without bytecode)."""
    dst = tmp_path / "jetnh"
    shutil.copytree(ROOT, dst, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return dst


def test_a_copy_hashes_as_the_package(package):
    assert source_hash(package) == source_hash(ROOT)


def test_an_edited_comment_in_principles_changes_the_hash(package):
    before = source_hash(package)
    path = package / "mechanics" / "principles.py"
    path.write_text(path.read_text(encoding="utf-8") + "# an edit\n", encoding="utf-8")
    assert source_hash(package) != before


def test_an_edited_constant_in_principles_changes_the_hash(package):
    """Suslov's kappa decides how the multipliers weigh the constraint Hessians: a change
    of it changes the derived equations, so it must change the key."""
    before = source_hash(package)
    path = package / "mechanics" / "principles.py"
    text = path.read_text(encoding="utf-8")
    assert text.count('kappa="momenta"') == 1
    path.write_text(text.replace('kappa="momenta"', 'kappa="multipliers"'), encoding="utf-8")
    assert source_hash(package) != before


def test_a_moved_file_changes_the_hash(package):
    before = source_hash(package)
    (package / "algebra" / "zero.py").rename(package / "geometry" / "zero.py")
    assert source_hash(package) != before


def test_a_new_file_changes_the_hash_and_bytecode_does_not(package):
    before = source_hash(package)
    (package / "numeric" / "__pycache__").mkdir()
    (package / "numeric" / "__pycache__" / "scene.cpython-312.pyc").write_bytes(b"\0" * 8)
    assert source_hash(package) == before
    (package / "numeric" / "methods" / "euler.py").write_text("", encoding="utf-8")
    assert source_hash(package) != before


def test_the_kernel_key_carries_the_source_hash(monkeypatch):
    from jetnh import models

    system = models.get("knife_edge")
    key = KernelSpec(system, "chetaev", {}).key
    monkeypatch.setattr(spec, "_derivation_source_hash", lambda: "0" * 16)
    assert KernelSpec(system, "chetaev", {}).key != key


def test_the_key_hashes_the_whole_package():
    """The hash in the key is the installed package's, all of it (not the directory of
    the module that computes it)."""
    assert spec._derivation_source_hash() == source_hash(ROOT)
