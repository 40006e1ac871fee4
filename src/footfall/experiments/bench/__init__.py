"""Benchmarks: figures printed, each against a baseline measured in the same process.

One module per benchmark (``footfall bench ...``): dense scoring against a
per-candidate loop (:mod:`~footfall.experiments.bench.scoring`), learning
against scikit-learn (:mod:`~footfall.experiments.bench.learning`), each
ranker's learning and scoring against the linear function
(:mod:`~footfall.experiments.bench.rankers`), the whole
walking stack against bare MuJoCo stepping (:mod:`~footfall.experiments.bench.sim`),
the walking expert with its placement error against without
(:mod:`~footfall.experiments.bench.expert`), the compiled bilinear sampling and
the compiled pose features' support terms against their NumPy definitions
(:mod:`~footfall.experiments.bench.sampling`, :mod:`~footfall.experiments.bench.pose`),
and a batch on a Ray cluster
against the local process pool (:mod:`~footfall.experiments.bench.executors`).
Tests never assert a time: these commands print them.
"""
