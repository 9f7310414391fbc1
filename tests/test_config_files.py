"""The shipped configuration files (configs/*.toml): each is what scripts/write_config_files.py writes
from the settings' dataclasses, sets nothing, and - uncommented - sets every default exactly; a job
file's settings take effect, nested presets included."""
import re
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from app.config import defaults_toml, load_toml
from app.jobs.settings import JobConfig
from app.predict.config import CELL_IMITATION

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "scripts"))
from write_config_files import FILES  # noqa: E402

SETTING = re.compile(r"^# (\[[\w.]+\]|\w+ = .*)$")


@pytest.mark.parametrize("name", sorted(FILES))
def test_a_shipped_file_is_its_dataclass_s_defaults_commented_out(name, tmp_path):
    cls, header = FILES[name]
    text = (ROOT / name).read_text()
    assert text == defaults_toml(cls, header), f"{name} is stale: run .venv/bin/python scripts/write_config_files.py"
    assert load_toml(cls, ROOT / name) == cls()  # sets nothing
    uncommented = tmp_path / "all.toml"
    uncommented.write_text("\n".join(line[2:] if SETTING.match(line) and not line.endswith("(unset)") else line
                                     for line in text.splitlines()))
    assert load_toml(cls, uncommented) == cls()  # every value shown is the default


def test_a_job_file_s_settings_take_effect_and_a_nested_table_starts_from_its_preset(tmp_path):
    path = tmp_path / "job.toml"
    path.write_text('attempts = 2\n[predict]\nmethod = "cpd"\ndemos = "my-demos/mug"\n'
                    '[predict.imitation]\niterations = 300\n[motion]\njoint_speed = 2.0\n')
    job = load_toml(JobConfig, path)
    assert job.attempts == 2 and job.method == "cpd" and job.predict.demos == Path("my-demos/mug")
    assert job.predict.imitation == replace(CELL_IMITATION, iterations=300)  # the cell's schedule, not the paper's
    assert job.motion.joint_speed == 2.0 and job.motion.lift_height == JobConfig().motion.lift_height


BAD_JOB_FILES = {  # what a file says -> what the one line must name
    '[predict]\nmethod = "ndf"\n': "unknown method 'ndf'",
    "attempts = 0\n": "attempts must be in [1, 100]",
    "place_contact_force = -1.0\n": "place_contact_force must be in (0, 1000] N",
    "[motion]\njoint_sped = 1.0\n": "unknown setting 'joint_sped' for MotionConfig",
    "[motion]\njoint_speed = -1.0\n": "joint_speed must be in (0, 3.15] rad/s, got -1.0",
    "[perception]\nz_range = [0.4, -0.03]\n": "z_range must be a range (low, high) with low < high",
    "[predict.imitation.candidates]\nmost = 0\n": "most must be in [1, 1000], got 0",
}


@pytest.mark.parametrize("text", sorted(BAD_JOB_FILES))
def test_a_bad_job_file_is_refused_in_one_line_naming_the_file_and_the_setting(tmp_path, text):
    path = tmp_path / "job.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=f"^{re.escape(str(path))}: ") as caught:
        load_toml(JobConfig, path)
    assert BAD_JOB_FILES[text] in str(caught.value) and "\n" not in str(caught.value)
