"""Test metrics of field weights on a `nift make-data` directory (SCF R^2 per band, occupancy accuracy).

Usage (repo root): .venv/bin/python scripts/evaluate_field.py data/gpu-test nif ndf runs/gpu/nif.pt
Weights are 'nif' / 'ndf' (the shipped ones) or paths; every sample of the data, 500 queries each.
"""
import sys

import numpy as np
import torch

from app.nift.field import load_field
from app.training.dataset import FieldData
from app.training.evaluate import evaluate

if len(sys.argv) < 3:
    sys.exit(__doc__)
torch.set_num_threads(2)
data = FieldData(sys.argv[1])
for weights in sys.argv[2:]:
    result = evaluate(load_field(weights), data, np.arange(data.n_samples), data.cloud.shape[1], 500)
    print(weights, {k: round(v, 4) if isinstance(v, float) else v for k, v in result.items()})
