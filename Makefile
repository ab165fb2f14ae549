# Two commands do all the set-up on a fresh machine:
#   make run    the machine-checked reproduction of the seed paper (papers/zhao2008)
#   make test   run the whole test suite (hypothesis profile "ci"; HYPOTHESIS_PROFILE=dev for more)
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: run test venv clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

venv: $(STAMP)

run: $(STAMP)
	$(BIN)/jetnh reproduce

test: $(STAMP)
	$(BIN)/python -m pytest -n 2 --dist loadfile -q

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis
