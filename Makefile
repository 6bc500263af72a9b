# Set-up and main entry points. `make test` and `make demo` work on a fresh Linux machine.
#
# PyTorch (CPU build) is installed first, from wherever pip finds it: pip's own configuration
# (a local wheel, a mirror), or TORCH_INDEX, a package index serving CPU builds, passed to that
# one install only, e.g. `make TORCH_INDEX=https://download.pytorch.org/whl/cpu test`.
# A CUDA build that arrives anyway is a warning with the disk space it takes, not a failure.
PYTHON ?= python3
VENV ?= .venv
# `make test`: the core and these extras (`make demo`: the core only)
EXTRAS ?= dev,ray,record
TORCH ?= torch==2.13.0
TORCH_INDEX ?=
BIN := $(VENV)/bin
CORE_STAMP := $(VENV)/.core-installed
STAMP := $(VENV)/.installed

.PHONY: demo test test-slow test-rllib lint bench docs clean

define CUDA_CHECK
import importlib.metadata as md, sys, torch
extra = [d for d in md.distributions()
         if (d.metadata["Name"] or "").lower().startswith(("nvidia-", "triton"))]
if torch.version.cuda or extra:
    files = [f.locate() for d in [md.distribution("torch"), *extra] for f in d.files or []]
    size = sum(p.stat().st_size for p in files if p.is_file()) / 1e9
    print(f"warning: PyTorch {torch.__version__} is a CUDA build: with {len(extra)} NVIDIA "
          f"packages it takes {size:.1f} GB installed. This project needs only the CPU build: "
          "make clean, then make TORCH_INDEX=<a CPU package index> (see README)", file=sys.stderr)
endef
export CUDA_CHECK

# The core: the env, the estimators, the follower, SB3 training.
$(CORE_STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --upgrade --quiet pip
	# CPU PyTorch first, so nothing later pulls a CUDA build.
	$(BIN)/python -m pip install --quiet $(if $(TORCH_INDEX),--index-url $(TORCH_INDEX)) '$(TORCH)'
	$(BIN)/python -m pip install --quiet -e .
	@$(BIN)/python -c "$$CUDA_CHECK"
	touch $(CORE_STAMP)

# The extras the tests need: dev (pytest, ruff, rl-zoo3, evo), ray, record (MCAP, Rerun).
$(STAMP): $(CORE_STAMP)
	$(BIN)/python -m pip install --quiet -e '.[$(EXTRAS)]'
	touch $(STAMP)

demo: $(CORE_STAMP)
	$(BIN)/stsf-gym demo

# The default tier (pyproject deselects the markers `slow` and `every_id`): minutes.
test: $(STAMP)
	$(BIN)/python -m pytest -q

# The second tier: subprocess runs, training, Ray, packaging, docs blocks, examples, and the
# every-id matrices. CI runs it after `make test`.
test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -m 'slow or every_id'

# RLlib pins its own Gymnasium release, so it gets a venv of its own.
test-rllib:
	$(MAKE) VENV=.venv-rllib EXTRAS=dev,rllib .venv-rllib/.installed
	.venv-rllib/bin/python -m pytest -q tests/clients/test_rllib.py

# The documentation site (mkdocs.yml): strict, so a broken link, a page missing from the
# navigation or a public name without a docstring fails. Installs the docs extra once.
DOCS_STAMP := $(VENV)/.docs-installed
$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[$(EXTRAS),docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

# ruff's lint and format checks, and mypy on the package laid out as installed: the link tree
# setuptools makes for a strict editable install (build/__editable__.*), which a type checker
# or an IDE reads as one namespace (stsf_gym.envs, stsf_gym.agents, ...).
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	rm -rf build/__editable__.* && mkdir -p build/editable-wheel
	$(BIN)/python -c "from setuptools import setup; setup()" -q editable_wheel --mode strict \
		--dist-dir build/editable-wheel >/dev/null 2>&1
	$(BIN)/mypy build/__editable__.*/stsf_gym

bench: $(STAMP)
	$(BIN)/stsf-gym bench

clean:
	rm -rf $(VENV) .venv-rllib out runs site build/api-src
