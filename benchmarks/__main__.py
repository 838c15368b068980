"""python -m benchmarks [--quick] [--repeat N] [--threads T] [--parts P ...] --out DIR"""
import sys

from .bench import main

sys.exit(main())
