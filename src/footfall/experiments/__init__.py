"""Experiments that prove the method: the offline experiment, the walking reproduction, its report, batches of runs and benchmarks."""
