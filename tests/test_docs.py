"""The documentation site's sources: every page is reachable from a toctree, every
gallery and how-to page is an executed notebook, the paper's report is included (not
copied), and no docstring refers to a file outside the repository.  ``make docs`` builds
the site (warnings are errors); CI runs it."""

import ast
import re
import tokenize
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def toctree_entries(page: Path) -> set:
    """The documents a page's toctrees list, relative to the docs directory."""
    text = page.read_text(encoding="utf-8")
    out = set()
    for block in re.findall(r"```\{toctree\}\n(.*?)```", text, flags=re.S):
        for line in block.splitlines():
            line = line.strip()
            if line and not line.startswith(":"):
                out.add(str((page.parent / line).relative_to(DOCS)))
    return out


def test_every_page_is_in_a_toctree():
    pages = {str(p.relative_to(DOCS).with_suffix("")) for p in DOCS.rglob("*.md")
             if "_build" not in p.parts}
    listed = set()
    for p in DOCS.rglob("*.md"):
        if "_build" not in p.parts:
            listed |= toctree_entries(p)
    assert pages - listed == {"index"}, sorted(pages - listed)
    assert listed <= pages, sorted(listed - pages)


@pytest.mark.parametrize("section", ["gallery", "howto"])
def test_gallery_and_howtos_are_executed_notebooks(section):
    notebooks = sorted(p for p in (DOCS / section).glob("*.md") if p.stem != "index")
    assert notebooks
    listed = toctree_entries(DOCS / section / "index.md")
    for nb in notebooks:
        assert f"{section}/{nb.stem}" in listed, nb.name
        text = nb.read_text(encoding="utf-8")
        assert text.startswith("---\nfile_format: mystnb\n"), nb.name    # executed
        assert "```{code-cell} ipython3" in text, nb.name


def test_the_gallery_has_the_promised_examples():
    listed = toctree_entries(DOCS / "gallery" / "index.md")
    assert {"gallery/rolling_disk", "gallery/appell_hamel", "gallery/heisenberg",
            "gallery/sweep_map", "gallery/from_mechanics", "gallery/from_kane",
            "gallery/conserved"} <= listed
    text = {p.stem: p.read_text(encoding="utf-8") for p in (DOCS / "gallery").glob("*.md")}
    assert "jn.from_mechanics(" in text["from_mechanics"]
    assert all(w in text["from_kane"] for w in ("KanesMethod(", "add_joints(", "jn.compare("))
    assert "c.singular" in text["appell_hamel"]
    assert all(p in text["rolling_disk"] for p in ("vakonomic", "holder", "suslov"))
    assert "jn.conserved_quantities(" in text["conserved"]
    assert "client=" not in text["sweep_map"]                  # local, no Dask


def test_the_report_is_included_not_copied():
    page = (DOCS / "reproduction.md").read_text(encoding="utf-8")
    assert "```{include} ../papers/zhao2008/report.md" in page
    assert (DOCS / ".." / "papers" / "zhao2008" / "report.md").resolve().is_file()
    assert len(page) < 2000


def test_docs_builds_keep_their_caches_in_the_build_directory():
    conf = (DOCS / "conf.py").read_text(encoding="utf-8")
    assert 'os.environ.setdefault("JETNH_CACHE", str(HERE / "_build"' in conf
    assert 'nb_execution_cache_path = str(HERE / "_build"' in conf
    make = (ROOT / "Makefile").read_text(encoding="utf-8")
    assert "sphinx-build -b html -W --keep-going -n" in make
    assert "make docs" in (ROOT / ".ci" / "run").read_text(encoding="utf-8")


# ---------------------------------------------------------------------- docstrings
def docstrings():
    """(file, name, docstring) of every module, class and function in the package, the
    paper's reproduction and the benchmarks."""
    for base in ("jetnh", "papers", "benchmarks"):
        for path in sorted((ROOT / base).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            for node in ast.walk(tree):
                if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef,
                                     ast.AsyncFunctionDef)):
                    doc = ast.get_docstring(node)
                    if doc:
                        yield path.relative_to(ROOT), getattr(node, "name", "module"), doc


#: what names a file outside the repository: the design notes, shared folders, the
#: workplace's paths and the issue tracker's files
OUTSIDE = re.compile(r"DESIGN\.md|\bshared/|\bseed/|/work/|\bnotes/|issue\s*\d+\.md",
                     re.I)


def test_docstrings_refer_to_no_files_outside_the_repository():
    assert OUTSIDE.search("as in DESIGN.md section 4") and not OUTSIDE.search("report.md")
    bad = [f"{f}:{name}: {m.group(0)}" for f, name, doc in docstrings()
           for m in OUTSIDE.finditer(doc)]
    assert not bad, bad



def test_comments_refer_to_no_files_outside_the_repository():
    bad = []
    for base in ("jetnh", "papers", "benchmarks"):
        for path in sorted((ROOT / base).rglob("*.py")):
            with tokenize.open(path) as fh:
                bad += [f"{path.relative_to(ROOT)}:{tok.start[0]}: {tok.string}"
                        for tok in tokenize.generate_tokens(fh.readline)
                        if tok.type == tokenize.COMMENT and OUTSIDE.search(tok.string)]
    assert not bad, bad
