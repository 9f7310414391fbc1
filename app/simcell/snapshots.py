"""Key-frame pictures of the simulated cell (PyBullet's TinyRenderer): a PNG strip of a job."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from app.io_utils import atomic_path
from hardware.bullet import p
from hardware.sim.world import SimWorld

VIEW_EYE = (1.25, 0.75, 0.75)  # a viewer in front of the robot, to its left, above the table
VIEW_TARGET = (0.35, 0.0, 0.12)


def snapshot(world: SimWorld, label: str = "", size: tuple[int, int] = (320, 240), eye=VIEW_EYE,
             target=VIEW_TARGET) -> np.ndarray:
    """An RGB picture (H, W, 3) uint8 of the world from a fixed viewpoint, with the label burnt in."""
    cid = world.require()
    w, h = size
    view = p.computeViewMatrix(eye, target, [0, 0, 1], physicsClientId=cid)
    proj = p.computeProjectionMatrixFOV(50.0, w / h, 0.05, 5.0, physicsClientId=cid)
    rgb = np.asarray(p.getCameraImage(w, h, view, proj, renderer=p.ER_TINY_RENDERER, physicsClientId=cid)[2],
                     dtype=np.uint8).reshape(h, w, 4)[:, :, :3].copy()
    if label:
        _caption(rgb, label)
    return rgb


def _caption(image: np.ndarray, text: str) -> None:
    """Burn a caption into the top-left corner (matplotlib's Agg text, no GUI)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    h, w = image.shape[:2]
    fig = Figure(figsize=(w / 100, 0.22), dpi=100)
    fig.patch.set_facecolor("white")
    fig.text(0.01, 0.2, text, fontsize=9)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    band = np.asarray(canvas.buffer_rgba())[:, :, :3]
    image[: band.shape[0], : min(w, band.shape[1])] = band[:, :w]


def save_strip(frames: list[np.ndarray], path: Path, columns: int = 4) -> Path:
    """Tile frames into rows of `columns` and write one PNG (atomically)."""
    import matplotlib.image

    if not frames:
        raise ValueError("no key frames to save")
    if Path(path).suffix.lower() != ".png":
        raise ValueError(f"{path}: the key-frame strip is written as PNG; give a .png path")
    h, w, _ = frames[0].shape
    rows = -(-len(frames) // columns)
    sheet = np.full((rows * h, min(columns, len(frames)) * w, 3), 255, dtype=np.uint8)
    for i, frame in enumerate(frames):
        r, c = divmod(i, columns)
        sheet[r * h:(r + 1) * h, c * w:(c + 1) * w] = frame
    with atomic_path(Path(path)) as tmp:
        matplotlib.image.imsave(tmp, sheet, format="png")
    return Path(path)
