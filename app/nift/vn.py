"""Vector Neuron layers (Deng et al., ICCV 2021): SO(3)-equivariant building blocks.

A vector-neuron feature is a list of C 3-vectors per point, stored channels-last as a tensor
(B, ..., 3, C): any leading axes (points, neighbours), then the 3-vector axis, then the C
channels - so a VN linear layer is one plain matrix product on the last axis (channels-first
einsums measured 3-5x slower on CPU). Every layer here commutes with a rotation R acting on
the 3-vector axis:  layer(R x) = R layer(x).

- VNLinear:     x' = W x              (mixes channels only; no bias, a bias would break equivariance)
- VNLeakyReLU:  with a learned direction k = U x per channel (or one shared by all channels),
                x' = a x + (1 - a) (x                    if <x, k> >= 0
                                    x - <x, k>/|k|^2 k   otherwise)      (a = negative slope)
- VNResnetBlock: shortcut(x) + fc1(relu1(fc0(relu0(x))))
- vn_invariant: <x, V x> per channel, a rotation-invariant scalar per channel.
"""
from __future__ import annotations

import torch
from torch import nn

EPS = 1e-6


class VNLinear(nn.Module):
    """x (B, ..., 3, C_in) -> W x (B, ..., 3, C_out)."""

    def __init__(self, c_in: int, c_out: int) -> None:
        super().__init__()
        self.weight = nn.Parameter(torch.empty(c_out, c_in))
        nn.init.kaiming_uniform_(self.weight, a=5 ** 0.5)  # nn.Linear's default initialisation

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.nn.functional.linear(x, self.weight)


class VNLeakyReLU(nn.Module):
    """Leaky ReLU on the half-space of a learned direction per channel (Deng et al. Eq. 4)."""

    def __init__(self, channels: int, negative_slope: float = 0.2, shared: bool = False) -> None:
        super().__init__()
        self.direction = VNLinear(channels, 1 if shared else channels)  # shared: one direction for all
        self.negative_slope = negative_slope

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        k = self.direction(x)  # (B, ..., 3, C)
        dot = (x * k).sum(dim=-2, keepdim=True)  # (B, ..., 1, C)
        k_sq = (k * k).sum(dim=-2, keepdim=True)
        projected = x - (dot / (k_sq + EPS)) * k
        rectified = torch.where(dot >= 0, x, projected)
        return self.negative_slope * x + (1.0 - self.negative_slope) * rectified


class VNResnetBlock(nn.Module):
    """Two VN linear layers with VN leaky ReLUs before each and a (linear) shortcut."""

    def __init__(self, c_in: int, c_out: int, shared: bool = False) -> None:
        super().__init__()
        hidden = c_out
        self.act0 = VNLeakyReLU(c_in, shared=shared)
        self.fc0 = VNLinear(c_in, hidden)
        self.act1 = VNLeakyReLU(hidden, shared=shared)
        self.fc1 = VNLinear(hidden, c_out)
        self.shortcut = VNLinear(c_in, c_out) if c_in != c_out else nn.Identity()
        nn.init.zeros_(self.fc1.weight)  # the block starts as its shortcut

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.shortcut(x) + self.fc1(self.act1(self.fc0(self.act0(x))))


class VNInvariant(nn.Module):
    """Per-channel invariant <x, V x>: (B, ..., 3, C) -> (B, ..., C)."""

    def __init__(self, channels: int) -> None:
        super().__init__()
        self.frame = VNLinear(channels, channels)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return (x * self.frame(x)).sum(dim=-2)
