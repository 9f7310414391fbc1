"""The calibration target: a ChArUco board (OpenCV), its printable image and its detection."""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from hardware.interfaces import CameraIntrinsics


@dataclass(frozen=True)
class BoardSpec:
    """A ChArUco board: squares (columns, rows), square and marker sizes in metres, dictionary."""

    squares: tuple[int, int] = (5, 4)
    square: float = 0.05
    marker: float = 0.038
    dictionary: int = cv2.aruco.DICT_4X4_50

    @property
    def size(self) -> tuple[float, float]:
        """(width, height) of the board in metres."""
        return self.squares[0] * self.square, self.squares[1] * self.square

    def board(self) -> cv2.aruco.CharucoBoard:
        return cv2.aruco.CharucoBoard(self.squares, self.square, self.marker,
                                      cv2.aruco.getPredefinedDictionary(self.dictionary))

    def image(self, px_per_m: int = 4000) -> np.ndarray:
        """Printable image (grey, uint8); pixel (u, v) is board point (u, v) / px_per_m."""
        w, h = self.size
        return self.board().generateImage((int(w * px_per_m), int(h * px_per_m)), marginSize=0)


@dataclass(frozen=True)
class Detection:
    """A board seen in one image: its pose, the matched corners and the PnP fit."""

    T_cam_board: np.ndarray  # (4, 4)
    object_points: np.ndarray  # (M, 3) board frame
    image_points: np.ndarray  # (M, 2) pixels
    rms_px: float


def detect_board(color: np.ndarray, intrinsics: CameraIntrinsics, spec: BoardSpec,
                 min_corners: int = 6) -> Detection | None:
    """The board's pose and corners in a colour image, or None if fewer than min_corners are seen.

    Board frame (OpenCV's): origin at a board corner, x along the columns, y along the rows,
    z into the board.
    """
    gray = cv2.cvtColor(np.ascontiguousarray(color), cv2.COLOR_RGB2GRAY)
    board = spec.board()
    corners, ids, _, _ = cv2.aruco.CharucoDetector(board).detectBoard(gray)
    if ids is None or len(ids) < min_corners:
        return None
    obj, img = board.matchImagePoints(corners, ids)
    K, dist = intrinsics.matrix, np.zeros(5)
    ok, rvec, tvec = cv2.solvePnP(obj, img, K, dist, flags=cv2.SOLVEPNP_ITERATIVE)
    if not ok:
        return None
    projected, _ = cv2.projectPoints(obj, rvec, tvec, K, dist)
    rms = float(np.sqrt(np.mean(np.sum((projected.reshape(-1, 2) - img.reshape(-1, 2)) ** 2, axis=1))))
    T = np.eye(4)
    T[:3, :3] = cv2.Rodrigues(rvec)[0]
    T[:3, 3] = tvec.ravel()
    return Detection(T, obj.reshape(-1, 3).astype(np.float64), img.reshape(-1, 2).astype(np.float64), rms)
