# The chapter's commands. Each target sets up what it needs first.
#   make chapter  the main job: all six notebooks at the default config -> runs/chapter/
#   make test     the test suite (runs every notebook in smoke mode, checks the release)
#   make test-fast  the tests not marked slow, for the edit-test loop (under 3 min on 2 cores): no
#                 notebook executed, no kernel, sandbox or browser started, no system package needed
#   make lint     ruff (pyproject.toml [tool.ruff]); CI runs it before make test
#   make run      the pipeline alone, seed 0, default config -> runs/seed0/metrics.json
#   make release  regenerate the student notebooks/ from solutions/ (nbgrader)
#   make grade    grade a class: make grade SUBMISSIONS=lms_download.zip [SCHEDULER=tcp://host:8786] [REGRADE=1]
#                 [JOBS=n] [TIMEOUT=seconds per cell] [CONFINE=unconfined: trusted notebooks only, with a warning]
#                 [COURSE=dir] -> course/ (or COURSE): grades.csv, report.csv, canvas_import.csv,
#                 moodle_import.csv, class_report.html, to_grade.csv, feedback/, feedback_return/
#   make gradescope  the Gradescope autograder zip -> runs/gradescope/autograder.zip [OUT=path.zip]
#                 [CONFINE=allow: grade unconfined where no sandbox starts; default: require one]
#   make icu      PyICU, which grading needs to find look-alike student ids (make test and make grade run it)
#   make browser  Chromium and Playwright, for the feedback pages' browser test (make test runs it)
#   make lab      JupyterLab on the student notebooks (instructors: jupyter lab solutions/)
#   make bench    speed figures -> benchmarks/wallclock.csv
#   make meta     re-measure seeds 0-2 and the horizon sweep -> meta.yaml
#   make times    make chapter, and record each notebook's measured time -> pusht/nb/times.json
#   make pair     sync solutions/*.ipynb with their text twins text/solutions/*.py (jupytext)
#   make claims   run notebooks 03-06 on seeds 0-9, record every claim they check -> benchmarks/claims.*
#   make site     make chapter, then the chapter site (Jupyter Book 1.x, offline) -> runs/site/html/index.html
#   make lanes    the slow lanes CI runs after make test: the smoke site in a real browser, the learner's
#                 path through JupyterLab, Colab's stack (make colab-check)
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

export PATH := $(abspath $(VENV))/bin:$(PATH)

.PHONY: setup sandbox icu browser chapter run test test-fast lint bench meta claims pair times release grade lab clean \
        site site-deps site-smoke lanes colab-check gradescope

setup: $(STAMP)

# Grading confines student code with bubblewrap (Debian/Ubuntu package "bubblewrap"). Installed
# here when we are root and it is missing; otherwise grading warns that code is not confined.
sandbox:
	@command -v bwrap >/dev/null 2>&1 || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 \
	  && (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq bubblewrap >/dev/null) ; } \
	  || echo "note: bubblewrap is not installed (sudo apt-get install bubblewrap): grading cannot confine student code"

# Look-alike student ids (victim2 and a Cyrillic vіctim2) are found with ICU's Unicode data through
# PyICU, which compiles against the system's ICU (Debian/Ubuntu packages libicu-dev and pkg-config;
# the build takes about a minute). Installed apart from `make setup`, so that a laptop without ICU
# still sets up; without it, grading goes on and warns that look-alike ids were not checked. As root
# with apt-get (CI), the system packages are installed first. REQUIRE_ICU=1 (.ci/run sets it) makes
# a failed install an error. The pin is in requirements.txt, as a comment that pip does not read.
PYICU := $(shell grep -o 'PyICU==[0-9][0-9.]*' requirements.txt)
APT   := DEBIAN_FRONTEND=noninteractive apt-get -qq -o DPkg::Lock::Timeout=300

icu: setup
	@$(PY) -c "import icu, sys; sys.exit(icu.VERSION != '$(patsubst PyICU==%,%,$(PYICU))')" 2>/dev/null || { \
	  need=""; pkg-config --exists icu-i18n 2>/dev/null || need="libicu-dev pkg-config"; \
	  command -v c++ >/dev/null 2>&1 || need="$$need g++"; \
	  $(PY) -c "import os, sys, sysconfig; sys.exit(not os.path.exists(sysconfig.get_path('include') + '/Python.h'))" \
	    || need="$$need python3-dev"; \
	  if [ -n "$$need" ] && [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing $$need with apt-get, to build PyICU"; \
	    $(APT) install -y $$need >/dev/null 2>&1 || { $(APT) update && $(APT) install -y $$need >/dev/null; }; \
	  fi; \
	  echo "building $(PYICU) against the system's ICU (about a minute; log: $(VENV)/pyicu-build.log)"; \
	  $(PY) -m pip install "$(PYICU)" >$(VENV)/pyicu-build.log 2>&1 \
	  || { echo "note: $(PYICU) could not be built (see $(VENV)/pyicu-build.log): grading will not check" \
	            "look-alike student ids. Install ICU's development files (Debian/Ubuntu: sudo apt-get install" \
	            "libicu-dev pkg-config; macOS: brew install icu4c pkg-config, and add" \
	            "\$$(brew --prefix)/opt/icu4c/lib/pkgconfig to PKG_CONFIG_PATH), then run make icu"; \
	       [ -z "$(REQUIRE_ICU)" ]; }; }

# The feedback pages' browser test (tests/test_feedback_browser.py) opens a hostile notebook's pages
# in headless Chromium through Playwright: Debian's `chromium` package, installed here when we are
# root with apt-get (about 30 s and 400 MB with its libraries), and the Python package playwright
# (a 50 MB wheel, 170 MB installed, that `make setup` and a course laptop never need: its pin is in
# requirements.txt as a comment that pip does not read, and this target installs it). Playwright is
# pointed at /usr/bin/chromium and never downloads a browser of its own. Without either the test is
# skipped with a note; REQUIRE_BROWSER=1 (.ci/run sets it) makes a failed install an error.
PLAYWRIGHT := $(shell grep -o 'playwright==[0-9][0-9.]*' requirements.txt)

browser: setup
	@[ -x /usr/bin/chromium ] || { [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 \
	  && echo "installing chromium with apt-get, for the feedback pages' browser test" \
	  && { $(APT) install -y chromium >/dev/null 2>&1 || { $(APT) update && $(APT) install -y chromium >/dev/null; }; }; } \
	  || { echo "note: chromium is not installed (sudo apt-get install chromium): the feedback pages'" \
	            "browser test is skipped"; [ -z "$(REQUIRE_BROWSER)" ]; }
	@$(PY) -c "import importlib.metadata as m, sys; sys.exit(m.version('playwright') != '$(patsubst playwright==%,%,$(PLAYWRIGHT))')" \
	    2>/dev/null || $(PY) -m pip install "$(PLAYWRIGHT)" >$(VENV)/playwright-install.log 2>&1 \
	  || { echo "note: $(PLAYWRIGHT) could not be installed (see $(VENV)/playwright-install.log): the" \
	            "feedback pages' browser test is skipped"; [ -z "$(REQUIRE_BROWSER)" ]; }

$(STAMP): requirements.txt pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet -r requirements.txt
	$(PY) -m pip install --quiet --no-deps -e .
	@# rfc3987-syntax, an optional extra of jsonschema that jupyter-events pulls in, builds a parser
	@# when imported: 2.8 s added to every process that imports nbformat (papermill, the grader,
	@# each nbgrader step; benchmarks/grading_wallclock.txt). Nothing here validates IRIs, and
	@# without it jsonschema skips only that one format check.
	$(PY) -m pip uninstall --quiet --yes rfc3987-syntax 2>/dev/null || true
	touch $(STAMP)

chapter: setup
	$(PY) -m scripts.chapter --out runs/chapter

times: setup
	$(PY) -m scripts.chapter --out runs/chapter --record-times

run: setup
	$(PY) -m pusht.dreamer --seed 0 --out runs/seed0

test: setup sandbox icu browser
	$(PY) -m pytest -q --durations=30   # the 30 slowest tests, named in every CI log

# The fast lane: the tests not marked `slow` (pyproject.toml says what slow means; tests/conftest.py
# marks the tests that ask for the executed notebooks, PyICU or Chromium, and the lanes; the other
# slow tests say so themselves). It needs only `make setup`. make test still runs every test.
test-fast: setup
	$(PY) -m pytest -q -m 'not slow'

lint: setup
	$(VENV)/bin/ruff check .

bench: setup
	$(PY) -m benchmarks.bench

meta: setup
	$(PY) -m scripts.record_meta

pair: setup
	$(VENV)/bin/jupytext --sync solutions/*.ipynb

claims: setup
	$(PY) -m scripts.claims --record

# The chapter site is built by Jupyter Book 1.x (Sphinx), which builds offline; Jupyter Book 2
# fetches its theme at build time. Its pins are in requirements.txt as comments that pip does not
# read (a laptop that never builds the site does not need Sphinx): this target installs them.
SITE_PINS := $(shell grep -o -E '(jupyter-book|sphinx-mathjax-offline)==[0-9][0-9a-z.]*' requirements.txt)

site-deps: setup
	@$(PY) -c "import importlib.metadata as m, sys; want = dict(p.split('==') for p in '$(SITE_PINS)'.split()); \
	  sys.exit(any(m.version(k) != v for k, v in want.items()))" 2>/dev/null \
	  || $(PY) -m pip install --quiet $(SITE_PINS)

site: chapter site-deps
	$(PY) -m chapter_site --run runs/chapter --out runs/site

# CI's site: the smoke run (seconds per notebook), built the same way.
site-smoke: setup site-deps
	$(PY) -m scripts.chapter --smoke --out runs/chapter-smoke
	$(PY) -m chapter_site --run runs/chapter-smoke --out runs/site-smoke

# The slow lanes (.ci/lanes): the tests marked `lane`, with what they need installed first:
# tests/test_site_browser.py (the smoke site in Chromium), tests/test_learner_path.py (JupyterLab, then
# the grader) and tests/test_colab_lane.py (which runs make colab-check's script).
lanes: setup browser site-smoke
	SITE_HTML=runs/site-smoke/html $(PY) -m pytest -q -m lane

release: setup
	$(PY) -m scripts.release

grade: setup sandbox icu
	@test -n "$(SUBMISSIONS)" || (echo "usage: make grade SUBMISSIONS=path/to/submissions.zip" && exit 2)
	$(PY) -m autograde.grade "$(SUBMISSIONS)" $(if $(COURSE),--course "$(COURSE)") $(if $(SCHEDULER),--scheduler $(SCHEDULER)) \
	  $(if $(REGRADE),--regrade) $(if $(JOBS),--jobs $(JOBS)) $(if $(TIMEOUT),--timeout $(TIMEOUT)) \
	  $(if $(filter unconfined,$(CONFINE)),--no-confine)

# The Gradescope autograder (autograde/gradescope.py): setup.sh and run_autograder at the zip's root,
# what grading needs of this package at the commit built (no solutions, tests or site builder). Upload
# it on the assignment's Configure Autograder page (docs/gradescope.md). OUT defaults to
# runs/gradescope/autograder.zip. By default the bundle grades nothing where no sandbox starts;
# CONFINE=allow builds one that grades there unconfined, with a warning now and in every result.
CONFINE ?= require
gradescope: setup
	$(PY) -m autograde.gradescope build "$(if $(OUT),$(OUT),runs/gradescope/autograder.zip)" --confine "$(CONFINE)"

lab: setup
	$(VENV)/bin/jupyter lab notebooks/

# The Colab lane: every notebook in smoke mode on Colab's Python and packages (colab/stack.txt),
# each alone in an empty folder, its package installed by its own Colab install cell from a local
# snapshot of this working tree. Makes .venv-colab the first time (Python 3.13 from pyenv or PATH;
# several GB, torch's CUDA build from PyPI), then reuses it while colab/stack.txt is unchanged.
colab-check: setup
	$(PY) -m scripts.colab_check

clean:
	rm -rf runs .pytest_cache .ruff_cache
