"""Benchmarks: geometry throughput now; the success-rate tables later."""
