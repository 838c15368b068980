"""The benchmarks of thinburn (docs/bench.md), kept out of the installed package: run from the
repository root as ``python -m benchmarks --out DIR``. ``bench`` is the driver and the accuracy
parts; ``fronts``, ``motion``, ``perf`` and ``threads`` are the other parts."""
