"""Benchmark scripts. Each writes JSON and a markdown table under
``benchmarks/results/`` and reports ratios measured side by side in one run."""
