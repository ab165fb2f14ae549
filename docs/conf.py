"""Sphinx configuration of the jetnh documentation (``make docs``)."""

import logging
import os
from pathlib import Path

import jetnh

HERE = Path(__file__).resolve().parent
# compiled kernels of the executed pages go to the build directory, not the user's cache
os.environ.setdefault("JETNH_CACHE", str(HERE / "_build" / "jetnh-cache"))

# the notebooks' kernels read their IPython profile from the build directory: a clean
# profile (no user start-up files) whose kernel logs errors only.  The kernel's one
# warning is that it talks to the build over local TCP without encryption (myst-nb
# starts it; the build is a local, short-lived process), printed once per page.
IPYTHONDIR = HERE / "_build" / "ipython"
(IPYTHONDIR / "profile_default").mkdir(parents=True, exist_ok=True)
(IPYTHONDIR / "profile_default" / "ipython_kernel_config.py").write_text(
    'c.IPKernelApp.log_level = "ERROR"\n', encoding="utf-8")
os.environ["IPYTHONDIR"] = str(IPYTHONDIR)
# accessible-pygments (furo's code styles) sets the root logger to INFO when imported,
# which would print the notebook client's "Executing notebook" line for every page
logging.getLogger("traitlets").setLevel(logging.WARNING)

project = "jetnh"
author = "the jetnh developers"
copyright = "the jetnh developers"
release = version = jetnh.__version__

extensions = [
    "myst_nb",                       # MyST pages and notebooks, executed at build time
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    # MathJax 3 shipped with the site (copied into _static/mathjax): formulas render
    # without network, and no page loads a script from elsewhere
    "sphinx-mathjax-offline",
]
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]
suppress_warnings = ["myst.header"]    # the included report starts below its own level

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# executed notebooks: cached in the build directory only, so a clean build runs them all
nb_execution_mode = "cache"
nb_execution_cache_path = str(HERE / "_build" / ".jupyter_cache")
nb_execution_timeout = 300
nb_execution_show_tb = True
nb_merge_streams = True

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False}

# warnings are errors (make docs: -W); references must resolve, except to the libraries
# jetnh builds on (no intersphinx: the build needs no network)
nitpicky = True
nitpick_ignore_regex = [
    (r"py:.*", r"(sympy|sp|numpy|np|pandas|pd|matplotlib|xarray|dask|distributed|scipy|numba"
               r"|mpmath|hypothesis|collections|typing|pathlib|concurrent|dataclasses|random)\b.*"),
    (r"py:.*", r"(int|float|str|bool|dict|list|tuple|set|frozenset|object|callable|None"
               r"|Exception|ValueError|RuntimeError|UserWarning|bytes|type|Path|Mapping"
               r"|Sequence|Iterable|Callable|Any|Expr|Symbol|Matrix|ndarray|DataFrame|Series"
               r"|Figure|Axes)\b.*"),
    # words of numpydoc type descriptions; private classes in type hints
    (r"py:.*", r"(sequence|array_like|expressions?|True|False)$"),
    (r"py:class", r"(.*\.)?_[A-Za-z]\w*$"),
]

html_theme = "furo"
html_title = f"jetnh {release}"
html_static_path = ["_static"]
html_css_files = ["jetnh.css"]   # outputs wrap or scroll inside the text column


# numpydoc sections (Parameters, Returns, Examples, ...) of functions, classes and
# modules, written as reST by napoleon; attributes and properties keep their text
# (napoleon would read a colon in their first line as a type)
from sphinx.ext.napoleon import Config as _NapoleonConfig  # noqa: E402
from sphinx.ext.napoleon.docstring import NumpyDocstring  # noqa: E402

NUMPYDOC = _NapoleonConfig(napoleon_google_docstring=False, napoleon_use_rtype=False,
                           napoleon_preprocess_types=True)


def numpydoc_sections(app, what, name, obj, options, lines):
    if what not in ("attribute", "property", "data"):
        lines[:] = NumpyDocstring(lines, NUMPYDOC, app, what, name, obj, options).lines()


def setup(app):
    app.connect("autodoc-process-docstring", numpydoc_sections)
    # MathJax on every page: the maths in jetnh's HTML displays (notebook outputs) is not
    # a Sphinx math node, so a page with no other formula would not load it
    app.set_html_assets_policy("always")
