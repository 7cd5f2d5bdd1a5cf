"""Benchmarks: every figure is a ratio against a baseline run side by side in the same process.

Run with ``make bench`` (``python -m benchmarks``). Each timing is the median of several runs;
the machines are shared and noisy, so compare ratios, not seconds.
"""
