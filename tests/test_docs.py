"""The documentation site's sources: every page is reachable from a toctree, every
gallery and how-to page is an executed notebook, the paper's report is included (not
copied), and no docstring refers to a file outside the repository.  ``make docs`` builds
the site (warnings are errors); CI runs it."""

import ast
import html.parser
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
            "gallery/two_point",
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


# ---------------------------------------------------------------------- offline maths
BUILT = DOCS / "_build" / "html"


def test_maths_is_typeset_by_the_mathjax_shipped_with_the_site():
    conf = (DOCS / "conf.py").read_text(encoding="utf-8")
    assert '"sphinx-mathjax-offline"' in conf and "mathjax_path" not in conf
    assert "sphinx-mathjax-offline>=" in (ROOT / "pyproject.toml").read_text(encoding="utf-8")


class _Page(html.parser.HTMLParser):
    """The remote scripts and style sheets of a page, its local scripts, and the TeX
    delimiters that stand outside math elements and code (MathJax would leave them raw:
    Sphinx has it typeset the math elements only)."""

    def __init__(self):
        super().__init__()
        self.remote, self.scripts, self.raw_tex, self.maths = [], [], [], 0
        self._open = []                      # per open element: is it a math element?

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        url = a.get("src") if tag == "script" else (
            a.get("href") if tag == "link" and "stylesheet" in (a.get("rel") or "") else None)
        if url and re.match(r"(https?:)?//", url):
            self.remote.append(url)
        elif url and tag == "script":
            self.scripts.append(url)
        if tag in ("br", "img", "meta", "link", "input", "hr", "source", "wbr"):
            return
        math = "math" in (a.get("class") or "").split()
        self.maths += math
        self._open.append(math or tag in ("pre", "code", "script", "style", "textarea"))

    def handle_endtag(self, tag):
        if self._open:
            self._open.pop()

    def handle_data(self, data):
        if not any(self._open) and re.search(r"\\\(|\\\[|\$\$", data):
            self.raw_tex.append(data.strip()[:80])


@pytest.mark.skipif(not (BUILT / "index.html").exists(),
                    reason="the site is not built here (make docs builds it, then runs this)")
def test_the_built_site_loads_nothing_remote_and_leaves_no_raw_tex():
    mathjax = BUILT / "_static" / "mathjax" / "tex-chtml.js"
    assert mathjax.is_file() and mathjax.stat().st_size > 100_000
    pages = sorted(BUILT.rglob("*.html"))
    with_maths = 0
    for page in pages:
        parsed = _Page()
        parsed.feed(page.read_text(encoding="utf-8"))
        rel = page.relative_to(BUILT)
        assert not parsed.remote, (rel, parsed.remote)
        for src in parsed.scripts:       # every local script is there
            assert (page.parent / src.split("?")[0]).resolve().is_file(), (rel, src)
        if parsed.maths:
            with_maths += 1
            assert any(s.split("?")[0].endswith("mathjax/tex-chtml.js")
                       for s in parsed.scripts), rel
        # outside code blocks, TeX stands only in math elements, which MathJax typesets
        assert not parsed.raw_tex, (rel, parsed.raw_tex[:3])
    assert with_maths >= 5, with_maths


# ---------------------------------------------------------------------- API pages
def test_docstring_examples_run():
    """The ``>>>`` examples of the package's docstrings, run as doctests."""
    import doctest
    import importlib
    import pkgutil

    import jetnh

    finder, runner = doctest.DocTestFinder(), doctest.DocTestRunner(
        optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    ran = 0
    for info in pkgutil.walk_packages(jetnh.__path__, "jetnh."):
        if "cli" in info.name.split(".")[1:2] or info.name.endswith("__main__"):
            continue
        module = importlib.import_module(info.name)
        for test in finder.find(module, module.__name__):
            if test.examples and test.name.startswith(info.name):
                runner.run(test)
                ran += len(test.examples)
    assert runner.failures == 0, runner.failures
    assert ran >= 10, ran


def test_public_contract_documents_its_parameters():
    """The public contract's docstrings have numpydoc Parameters sections naming every
    parameter of the signature (napoleon renders them on the API pages)."""
    import inspect

    import jetnh as jn

    public = [jn.JetSpace, jn.System, jn.System.equations, jn.Scene, jn.Scene.run,
              jn.Trajectory.plot, jn.Trajectory.at, jn.compare, jn.conserved_quantities,
              jn.noether_symmetries, jn.sweep.sweep, jn.from_mechanics, jn.linearize,
              jn.Linearization.replace, jn.Linearization.steady, jn.Linearization.along,
              jn.connect]
    for obj in public:
        doc = inspect.getdoc(obj)
        assert "\nParameters\n----------\n" in doc, obj.__qualname__
        section = doc.split("\nParameters\n----------\n")[1].split("\n\n")[0]
        documented = set()
        for line in section.splitlines():
            if line and not line[0].isspace():
                documented |= {n.strip(" *") for n in line.split(" : ")[0].split(",")}
        init = obj.__init__ if inspect.isclass(obj) else obj
        wanted = {n for n in inspect.signature(init).parameters if n != "self"}
        assert wanted <= documented, (obj.__qualname__, sorted(wanted - documented))


def test_docstring_code_renders_as_code():
    """No docstring of the package has an indented block that reStructuredText would set
    as a quotation (prose): code and formulas follow ``::`` or are ``>>>`` examples."""
    docutils_core = pytest.importorskip("docutils.core")
    napoleon = pytest.importorskip("sphinx.ext.napoleon")
    from docutils import nodes
    from sphinx.ext.napoleon.docstring import NumpyDocstring

    config = napoleon.Config(napoleon_use_rtype=False, napoleon_google_docstring=False)
    quoted = []
    for path, name, doc in docstrings():
        if path.parts[0] != "jetnh":
            continue
        tree = docutils_core.publish_doctree(
            str(NumpyDocstring(doc, config)),
            settings_overrides={"report_level": 5, "halt_level": 5})
        quoted += [f"{path}:{name}: {q.astext()[:60]!r}" for q in tree.findall(nodes.block_quote)]
    assert not quoted, quoted
