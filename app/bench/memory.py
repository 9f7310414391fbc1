"""The process's resident memory, for soak figures (Linux /proc; the peak from getrusage elsewhere)."""
from __future__ import annotations

import os
import resource

import numpy as np


def resident_mb() -> float:
    """Resident set size now, in MiB."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20
    except OSError:
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # kB on Linux; the peak


def growth_mb_per_job(rss: list[float]) -> float:
    """Slope (MiB a job) of a least-squares line through the second half of the samples: what the
    memory still grows by once caches (collision models, templates, fields) have filled."""
    tail = np.asarray(rss[len(rss) // 2:], float)
    if len(tail) < 2:
        return 0.0
    return float(np.polyfit(np.arange(len(tail)), tail, 1)[0])


def growth_across_refreshes(rss: list[float], every: int) -> float | None:
    """Slope (MiB a job) through the samples taken just after each fresh physics client (jobs 0,
    every, 2 every, ...): what no refresh frees, without the sawtooth of the shapes a refresh
    does free. None with fewer than two such samples."""
    at = np.arange(0, len(rss), every) if every > 0 else np.array([], int)
    if len(at) < 2:
        return None
    return float(np.polyfit(at, np.asarray(rss, float)[at], 1)[0])
