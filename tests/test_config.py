from pathlib import Path

import pytest

from app.config import load_toml
from app.sim.cell import CellConfig

SHIPPED = Path(__file__).resolve().parents[1] / "configs" / "cell.toml"


def test_shipped_cell_config_is_the_default():
    assert load_toml(CellConfig, SHIPPED) == CellConfig()


def test_edits_take_effect_and_typos_are_named(tmp_path):
    path = tmp_path / "cell.toml"
    path.write_text('camera_eye = [1.4, 0.1, 0.6]\n[arm]\ntracking_error_limit = 0.02\n')
    config = load_toml(CellConfig, path)
    assert config.camera_eye == (1.4, 0.1, 0.6) and config.arm.tracking_error_limit == 0.02
    assert config.world == CellConfig().world
    path.write_text("[arm]\ntracking_eror_limit = 0.02\n")
    with pytest.raises(ValueError, match="unknown setting 'tracking_eror_limit'"):
        load_toml(CellConfig, path)
    path.write_text("camera_eye = [1.4,\n")
    with pytest.raises(ValueError, match="not valid TOML"):
        load_toml(CellConfig, path)
    with pytest.raises(FileNotFoundError):
        load_toml(CellConfig, tmp_path / "none.toml")
