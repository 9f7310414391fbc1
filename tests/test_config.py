from pathlib import Path

import pytest

from app.config import load_toml
from app.simcell.cell import CellConfig

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


@pytest.mark.parametrize("text, message", [
    ('camera_noise = "yes"\n', "'camera_noise' must be true or false, got 'yes'"),
    ('[world]\ntime_step = "fast"\n', "'time_step' must be a number, got 'fast'"),
    ('[arm]\ncontact_force_limit = true\n', "'contact_force_limit' must be a number, got True"),
    ('[world]\ntime_step = nan\n', "'time_step' must be a number, got nan"),
    ("[world]\ntime_step = -0.004\n", "time_step must be in (0, 0.05] s, got -0.004"),
    ("[world]\ntime_step = 0.0\n", "time_step must be in (0, 0.05] s, got 0.0"),
    ("[world]\nsolver_iterations = 0\n", "solver_iterations must be in [1, 10000] iterations, got 0"),
    ("[arm]\ncontact_force_limit = -150.0\n", "contact_force_limit must be in (0, 10000] N, got -150.0"),
    ("[arm]\ntracking_error_limit = 5\n", "tracking_error_limit must be in (0, 1] rad, got 5.0"),
    ("[gripper]\ntimeout = -2\n", "timeout must be in (0, 60] s, got -2.0"),
])
def test_a_value_of_the_wrong_type_or_out_of_range_is_refused_naming_the_file_and_the_key(tmp_path, text, message):
    path = tmp_path / "cell.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=f"^{path}: ") as caught:
        load_toml(CellConfig, path)
    assert message in str(caught.value)


def test_an_integer_where_a_number_is_asked_is_taken_as_that_number(tmp_path):
    path = tmp_path / "cell.toml"
    path.write_text("[arm]\ncontact_force_limit = 150\n")
    limit = load_toml(CellConfig, path).arm.contact_force_limit
    assert limit == 150.0 and isinstance(limit, float)

