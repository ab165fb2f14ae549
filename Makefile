# Two commands do all the set-up on a fresh machine:
#   make run    the machine-checked reproduction of the seed paper (papers/zhao2008)
#   make test   run the whole test suite (hypothesis profile "ci"; HYPOTHESIS_PROFILE=dev for more)
# (installing compiles the integrator loops of a first run into jetnh's cache: jetnh cache warm)
# and one builds the documentation:
#   make docs   the site (Sphinx, notebooks executed) in docs/_build/html; warnings are errors,
#               and the built pages are checked to load nothing from the network
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
DOCS_STAMP := $(VENV)/.installed-docs

.PHONY: run test docs venv clean

# warming the cache: exit code 3 means the cache directory cannot be used (jetnh says
# why and how to fix it); the install works all the same (each run compiles its loops on
# first use), so make says so and goes on; any other failure stops it
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	$(BIN)/jetnh --quiet cache warm || { [ $$? -eq 3 ] && echo "make: installed without \
	warming the cache (see above); runs compile their loops on first use"; }
	touch $(STAMP)

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[test,docs]'
	touch $(DOCS_STAMP)

venv: $(STAMP)

run: $(STAMP)
	$(BIN)/jetnh reproduce

test: $(STAMP)
	$(BIN)/python -m pytest -n 2 --dist loadfile -q

# the executed notebooks and their compiled kernels are cached in docs/_build only
docs: $(DOCS_STAMP)
	$(BIN)/sphinx-build -b html -W --keep-going -n -q docs docs/_build/html
	$(BIN)/python -m pytest -q -p no:cacheprovider tests/test_docs.py -k "built_site or renders_as_code"
	@echo "the site is in docs/_build/html (open docs/_build/html/index.html)"

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis docs/_build
