# footfall: `make run` sets everything up and runs the main job (the walking experiment);
# `make test` runs the tests.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run offline demo test smoke bench clean chromium libgomp

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

# The main job: the paper's walking experiment end to end (walk, correct, learn, walk unseen
# terrain); resumes where it stopped. Report in out/reproduce/report.html.
run: $(STAMP)
	MPLBACKEND=Agg $(BIN)/footfall reproduce --out out/reproduce

# The offline experiment (learn from demonstrations, rank footholds on unseen terrain).
offline: $(STAMP)
	MPLBACKEND=Agg $(BIN)/footfall offline --out out/offline

# Pictures of a board scored densely with the hand-tuned reward.
demo: $(STAMP)
	MPLBACKEND=Agg $(BIN)/footfall demo --out out/demo

# The reproduction's small version (a few minutes), as CI's smoke test.
smoke: $(STAMP)
	rm -rf out/smoke
	MPLBACKEND=Agg $(BIN)/footfall reproduce --quick --out out/smoke
	test -s out/smoke/report.html

test: $(STAMP) chromium libgomp
	MPLBACKEND=Agg $(BIN)/python -m pytest -q -n auto

# Debian packages the tests need, installed with apt where missing and this user may (root, or
# sudo without a password): $(call apt_install,PACKAGE,TEST THAT IT IS PRESENT,WHAT LACKS IT).
define apt_install
	@$(2) || { \
	  if [ "$$(id -u)" = 0 ]; then SUDO=; elif sudo -n true 2>/dev/null; then SUDO="sudo -n"; \
	  else SUDO=none; fi; \
	  if [ "$$SUDO" != none ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing Debian's $(1)"; \
	    $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq \
	      $(1) >/dev/null; \
	  else echo "no $(1) and no apt-get to install it: $(3)"; fi; }
endef

# The teaching page's browser tests drive Debian's Chromium (Playwright cannot download its own
# browsers here). Without it those tests skip, unless FOOTFALL_REQUIRE_BROWSER is set (.ci/run
# sets it): then they fail.
chromium:
	$(call apt_install,chromium,command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1,the browser tests will skip)

# LightGBM (the boosted ranker) needs the GNU OpenMP runtime, Debian's libgomp1.
libgomp:
	$(call apt_install,libgomp1,ldconfig -p 2>/dev/null | grep -q 'libgomp\.so\.1',the boosted ranker cannot learn)

bench: $(STAMP) libgomp chromium
	$(BIN)/footfall bench scoring
	$(BIN)/footfall bench learning
	$(BIN)/footfall bench rankers
	$(BIN)/footfall bench expert
	$(BIN)/footfall bench sampling
	$(BIN)/footfall bench pose
	$(BIN)/footfall bench sim
	$(BIN)/footfall bench executors
	$(BIN)/footfall bench teach

clean:
	rm -rf $(VENV) out
