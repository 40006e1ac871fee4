# footfall: `make run` sets everything up and runs the main job (the walking experiment);
# `make test` runs the tests.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run offline demo test smoke bench clean

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

test: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/footfall bench scoring
	$(BIN)/footfall bench learning
	$(BIN)/footfall bench expert
	$(BIN)/footfall bench sim
	$(BIN)/footfall bench executors

clean:
	rm -rf $(VENV) out
