"""The neural field network: NIF when trained on SCF, NDF when trained on occupancy (paper Sec. III-A).

    f(x | O) = concat_{i=1..L} Phi^i(x, eps(O))                                   (Eq. 1)

eps is a Vector Neuron ResNet-PointNet (SO(3)-equivariant; translation is removed by centring
on the cloud's mean), giving a latent of C 3-vectors z (B, C, 3). The decoder Phi sees only
rotation-invariant inputs built from z and the centred query point q:

    h_0 = [ |q|^2,  <q, z_c> (c = 1..C),  <z_c, (V z)_c> (c = 1..C) ]             (1 + 2C values)

then an input layer and `decoder_blocks` residual blocks; the point feature is the concatenation
of h_0 and every layer's output (NDF's descriptor, which is also built this way), and a head maps
the last layer to the SCF c_0..c_n (n + 1 values) or to an occupancy logit.

Because every input to Phi is invariant, f(R x + t | R O + t) = f(x | O) for any rotation R and
translation t - the test suite checks this to 1e-4. Coordinates are multiplied by
`input_scale` (metres -> decimetres) inside the network so activations start near unit size.

Shapes: clouds (B, N, 3), query points (B, T, 3), latent z (B, C, 3), features (B, T, F) with
F = `FieldConfig.feature_dim`.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np
import torch
from torch import nn

from app.io_utils import atomic_path, write_json
from app.nift.vn import VNInvariant, VNLeakyReLU, VNLinear, VNResnetBlock

FORMAT = "nift-field/1"
TARGETS = ("scf", "occ")
WEIGHTS_DIR = Path(__file__).parent / "weights"
FUSED_FIELDS = WEIGHTS_DIR / "fused"  # nif.pt + ndf.pt trained on four fused views (the paper's setting)
SHIPPED = {"nif": "nif.pt", "ndf": "ndf.pt"}


@dataclass(frozen=True)
class FieldConfig:
    """Architecture and target of one field; stored inside every weights file."""

    target: str = "scf"  # "scf" (NIF) or "occ" (NDF)
    scf_order: int = 5  # SCF bands c_0..c_n predicted when target == "scf"
    latent: int = 64  # C, number of latent 3-vectors
    encoder_width: int = 64
    encoder_blocks: int = 4
    decoder_width: int = 64
    decoder_blocks: int = 4
    # k of the kNN local feature at the encoder input (see local_features). Needed: with the point
    # alone (k = 0) every per-point feature is a multiple of x_i, the mean pool of a centred cloud
    # is zero, and the encoder collapses (measured: it could not even overfit 8 samples).
    neighbours: int = 16
    shared_nonlinearity: bool = True  # one VN ReLU direction per point in the encoder blocks
    input_scale: float = 10.0  # metres -> network units
    # Clouds are encoded from at most this many points (a fixed random subset): the kNN features
    # depend on point density, so the encoder must see the density it was trained at (measured on
    # the test split: R^2 0.49 at the training size, 0.39 when fed all 1,024 points).
    cloud_points: int = 512

    def __post_init__(self) -> None:
        if self.target not in TARGETS:
            raise ValueError(f"unknown field target {self.target!r}; choose one of {', '.join(TARGETS)}")

    @property
    def out_dim(self) -> int:
        return self.scf_order + 1 if self.target == "scf" else 1

    @property
    def feature_dim(self) -> int:
        return 1 + 2 * self.latent + self.decoder_width * (self.decoder_blocks + 1)


@dataclass
class Latent:
    """An encoded cloud: the equivariant code z (B, C, 3) and the cloud centre (B, 3), network units."""

    z: torch.Tensor
    center: torch.Tensor


def local_features(p: torch.Tensor, k: int) -> torch.Tensor:
    """Equivariant per-point features of p (B, N, 3): (B, N, 3, 3) = [c_i - x_i, x_i, x_i x c_i],
    c_i the centroid of x_i's k nearest neighbours - the edge feature [x_j - x_i, x_i, x_i x x_j]
    of Deng et al. / NDF averaged over the neighbours before the first layer (it is linear in x_j),
    which keeps the first layer O(N) instead of O(N k): 4x faster training, measured."""
    with torch.no_grad():
        idx = torch.cdist(p, p).topk(k, dim=-1, largest=False).indices  # (B, N, k), self included
    nbr = torch.gather(p.unsqueeze(1).expand(-1, p.shape[1], -1, -1), 2,
                       idx.unsqueeze(-1).expand(-1, -1, -1, 3))  # (B, N, k, 3)
    c = nbr.mean(dim=2)  # (B, N, 3)
    return torch.stack([c - p, p, torch.cross(p, c, dim=-1)], dim=-1)  # (B, N, 3, 3)


class Encoder(nn.Module):
    """VN ResNet-PointNet: centred cloud (B, N, 3) -> z (B, C, 3)."""

    def __init__(self, cfg: FieldConfig) -> None:
        super().__init__()
        h = cfg.encoder_width
        self.k = cfg.neighbours
        self.fc_pos = VNLinear(3 if self.k else 1, h)
        self.act_pos = VNLeakyReLU(h, shared=cfg.shared_nonlinearity)
        self.fc_in = VNLinear(h, 2 * h)
        self.blocks = nn.ModuleList([VNResnetBlock(2 * h, h, cfg.shared_nonlinearity) for _ in range(cfg.encoder_blocks)])
        self.act_out = VNLeakyReLU(h)
        self.fc_out = VNLinear(h, cfg.latent)

    def forward(self, p: torch.Tensor) -> torch.Tensor:
        if self.k:
            x = self.act_pos(self.fc_pos(local_features(p, self.k)))  # (B, N, 3, H)
        else:
            x = self.act_pos(self.fc_pos(p.unsqueeze(-1)))  # (B, N, 3, H)
        x = self.fc_in(x)  # (B, N, 3, 2H)
        for i, block in enumerate(self.blocks):
            if i > 0:  # PointNet: every later block also sees the pooled global feature
                x = torch.cat([x, x.mean(dim=1, keepdim=True).expand_as(x)], dim=-1)
            x = block(x)  # (B, N, 3, H)
        return self.fc_out(self.act_out(x.mean(dim=1))).transpose(1, 2)  # (B, C, 3)


class ResnetBlockFC(nn.Module):
    """Plain residual block: x + fc1(relu(fc0(relu(x))))."""

    def __init__(self, width: int) -> None:
        super().__init__()
        self.fc0 = nn.Linear(width, width)
        self.fc1 = nn.Linear(width, width)
        nn.init.zeros_(self.fc1.weight)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.fc1(torch.relu(self.fc0(torch.relu(x))))


class Decoder(nn.Module):
    """Invariant decoder: (z (B, C, 3), q (B, T, 3)) -> (head (B, T, out), features (B, T, F))."""

    def __init__(self, cfg: FieldConfig) -> None:
        super().__init__()
        self.invariant = VNInvariant(cfg.latent)
        self.fc_in = nn.Linear(1 + 2 * cfg.latent, cfg.decoder_width)
        self.blocks = nn.ModuleList([ResnetBlockFC(cfg.decoder_width) for _ in range(cfg.decoder_blocks)])
        self.fc_out = nn.Linear(cfg.decoder_width, cfg.out_dim)

    def forward(self, z: torch.Tensor, q: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        T = q.shape[1]
        net_z = torch.einsum("btd,bcd->btc", q, z)  # (B, T, C)
        z_inv = self.invariant(z.transpose(1, 2)).unsqueeze(1).expand(-1, T, -1)  # (B, T, C)
        h = torch.cat([(q * q).sum(-1, keepdim=True), net_z, z_inv], dim=-1)  # (B, T, 1 + 2C)
        acts = [h]
        h = self.fc_in(h)
        acts.append(h)
        for block in self.blocks:
            h = block(h)
            acts.append(h)
        return self.fc_out(torch.relu(h)), torch.cat(acts, dim=-1)


class NeuralField(nn.Module):
    """Encoder + decoder with the user-facing API: encode, features, predict."""

    def __init__(self, config: FieldConfig) -> None:
        super().__init__()
        self.config = config
        self.encoder = Encoder(config)
        self.decoder = Decoder(config)
        # SCF bands differ in size by 10x; the head predicts them standardised with the training
        # data's per-band mean and std (set once before training, saved with the weights).
        self.register_buffer("target_mean", torch.zeros(config.out_dim))
        self.register_buffer("target_std", torch.ones(config.out_dim))

    def set_target_stats(self, mean: np.ndarray, std: np.ndarray) -> None:
        """Per-band SCF mean and std of the training data (SCF fields only)."""
        self.target_mean.copy_(torch.as_tensor(mean, dtype=torch.float32))
        self.target_std.copy_(torch.as_tensor(np.maximum(std, 1e-6), dtype=torch.float32))

    def standardise(self, scf: torch.Tensor) -> torch.Tensor:
        """SCF (..., n + 1) -> the head's standardised units."""
        return (scf - self.target_mean) / self.target_std

    @property
    def device(self) -> torch.device:
        return self.decoder.fc_in.weight.device

    def _tensor(self, a) -> torch.Tensor:
        t = torch.as_tensor(a, dtype=self.decoder.fc_in.weight.dtype, device=self.device)
        return t.unsqueeze(0) if t.dim() == 2 else t

    def encode(self, cloud) -> Latent:
        """Cloud (N, 3) or (B, N, 3), metres, numpy or tensor -> Latent (batch B, 1 for one cloud)."""
        p = self._tensor(cloud) * self.config.input_scale  # (B, N, 3)
        if p.shape[-1] != 3 or p.shape[1] == 0:
            raise ValueError(f"a cloud must be (N, 3) or (B, N, 3) with N > 0, got shape {tuple(p.shape)}")
        if not torch.isfinite(p).all():
            raise ValueError("the cloud contains NaN or inf")
        p = self.subsample(p)  # (B, n, 3), n <= cloud_points
        center = p.mean(dim=1)  # (B, 3)
        return Latent(self.encoder(p - center.unsqueeze(1)), center)

    def subsample(self, p: torch.Tensor) -> torch.Tensor:
        """(B, N, 3) -> (B, min(N, cloud_points), 3): the same random indices (seed 0) for every cloud, so
        a cloud always gives one latent, alone or in a batch, and a rotated copy an equivariant one."""
        N, n = p.shape[1], self.config.cloud_points
        if N <= n:
            return p
        pick = torch.randperm(N, generator=torch.Generator().manual_seed(0))[:n]  # (n,)
        return p[:, pick.to(p.device)]

    def _decode(self, latent: Latent, points) -> tuple[torch.Tensor, torch.Tensor]:
        q = self._tensor(points) * self.config.input_scale  # (B, T, 3)
        z, center = latent.z, latent.center
        if z.shape[0] == 1 and q.shape[0] > 1:  # one cloud, several point sets (imitation inits)
            z, center = z.expand(q.shape[0], -1, -1), center.expand(q.shape[0], -1)
        return self.decoder(z, q - center.unsqueeze(1))

    def features(self, latent: Latent, points) -> torch.Tensor:
        """Eq. 1: the concatenated decoder activations at points (B, T, 3) -> (B, T, feature_dim)."""
        return self._decode(latent, points)[1]

    def head(self, latent: Latent, points) -> torch.Tensor:
        """Raw head output (B, T, out_dim): standardised SCF, or occupancy logits."""
        return self._decode(latent, points)[0]

    def predict(self, latent: Latent, points) -> torch.Tensor:
        """SCF c_0..c_n (B, T, n + 1), or occupancy probability (B, T)."""
        return self.from_head(self.head(latent, points))

    def from_head(self, out: torch.Tensor) -> torch.Tensor:
        """Head output -> SCF (de-standardised) or occupancy probability."""
        if self.config.target == "scf":
            return out * self.target_std + self.target_mean
        return torch.sigmoid(out[..., 0])


def save_field(field: NeuralField, path: str | Path, card: dict | None = None) -> Path:
    """Write weights (format nift-field/1) atomically, and the model card beside them as JSON."""
    path = Path(path)
    state = {k: v.detach().cpu() for k, v in field.state_dict().items()}
    with atomic_path(path) as tmp:
        torch.save({"format": FORMAT, "config": asdict(field.config), "state": state}, tmp)
    if card is not None:
        write_json(path.with_suffix(".json"), card)
    return path


def field_path(name_or_path: str | Path) -> Path:
    """'nif' / 'ndf' -> the shipped weights; anything else is a path."""
    if str(name_or_path) in SHIPPED:
        return WEIGHTS_DIR / SHIPPED[str(name_or_path)]
    return Path(name_or_path)


def load_field(name_or_path: str | Path = "nif", device: str | torch.device = "cpu") -> NeuralField:
    """Load shipped ('nif', 'ndf') or saved weights, in eval mode; one-line errors for bad files."""
    path = field_path(name_or_path)
    if not path.is_file():
        raise FileNotFoundError(f"no field weights at {path}")
    try:
        blob = torch.load(path, map_location=device, weights_only=True)
    except Exception as exc:  # torch raises several types for truncated or foreign files
        raise ValueError(f"{path} is not a readable field weights file ({type(exc).__name__})") from None
    if not isinstance(blob, dict) or blob.get("format") != FORMAT:
        found = blob.get("format") if isinstance(blob, dict) else type(blob).__name__
        raise ValueError(f"{path}: expected format {FORMAT!r}, found {found!r}")
    known = {f.name for f in fields(FieldConfig)}
    config, state = blob.get("config"), blob.get("state")
    if not isinstance(config, dict) or not isinstance(state, dict) or not state:
        raise ValueError(f"{path}: a weights file needs a config and a non-empty state")
    unknown = set(config) - known
    if unknown:
        raise ValueError(f"{path}: unknown field config keys {sorted(unknown)}")
    try:
        field = NeuralField(FieldConfig(**config)).to(device)
        field.load_state_dict(state)
    except (TypeError, ValueError, RuntimeError) as exc:  # load_state_dict lists every missing key
        raise ValueError(f"{path}: the weights do not fit their config ({str(exc).splitlines()[0][:160]})") from None
    return field.eval()


_SHARED: dict[tuple, NeuralField] = {}


def shared_field(name_or_path: str | Path = "nif") -> NeuralField:
    """`load_field` for inference, read once per process and file version (path, size, mtime): a job
    imitates on every look, and reading the weights took 28 ms of each. Never train the returned field."""
    path = field_path(name_or_path)
    stat = path.stat() if path.is_file() else None
    key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns) if stat else None
    if key is None or key not in _SHARED:
        field = load_field(path)  # a missing or bad file raises its one-line error here
        if len(_SHARED) >= 8:  # a handful of weights files per process; never grows without bound
            _SHARED.clear()
        _SHARED[key] = field
    return _SHARED[key]


def read_card(name_or_path: str | Path = "nif") -> dict:
    """The model card JSON beside a weights file."""
    import json

    card = field_path(name_or_path).with_suffix(".json")
    if not card.is_file():
        raise FileNotFoundError(f"no model card at {card}")
    return json.loads(card.read_text())
