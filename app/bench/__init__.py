"""Benchmarks: geometry throughput, the field, imitation, the cell, executed jobs, and the paper's tables."""
