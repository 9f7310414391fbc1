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


def growth_across_refreshes(rss: list[float], fresh: list[int]) -> float | None:
    """Slope (MiB a job) through the samples rss[i] of the jobs i that ran first on a fresh physics
    client: what no refresh frees, without the sawtooth of the shapes a refresh does free. None
    with fewer than two such samples."""
    if len(fresh) < 2:
        return None
    return float(np.polyfit(fresh, np.asarray(rss, float)[fresh], 1)[0])
