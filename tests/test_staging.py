"""Teach-in writes that lose nothing: the staging folder swaps in whole, or not at all."""
import pytest

from app.cli import main
from app.tasks.staging import demo_count, staged, teach_mode


def _demos(directory, names):
    directory.mkdir(parents=True, exist_ok=True)
    for name in names:
        (directory / f"{name}.npz").write_bytes(name.encode())


def test_an_interrupted_session_leaves_the_demos_as_they_were(tmp_path):
    out = tmp_path / "mug"
    _demos(out, ["demo-00", "demo-01"])
    with pytest.raises(KeyboardInterrupt):
        with staged(out, "replace") as stage:
            (stage / "demo-00.npz").write_bytes(b"new")
            raise KeyboardInterrupt  # the operator's Ctrl-C half-way
    assert sorted(p.name for p in out.iterdir()) == ["demo-00.npz", "demo-01.npz"]
    assert (out / "demo-00.npz").read_bytes() == b"demo-00"
    assert [p.name for p in tmp_path.iterdir()] == ["mug"]  # no staging folder left behind


def test_replace_keeps_only_the_new_demos_and_add_keeps_both(tmp_path):
    out = tmp_path / "mug"
    _demos(out, ["demo-00", "demo-01"])
    with staged(out, "add") as stage:
        assert demo_count(stage) == 2  # the old ones are there to number after
        (stage / "demo-02.npz").write_bytes(b"new")
    assert sorted(p.name for p in out.iterdir()) == ["demo-00.npz", "demo-01.npz", "demo-02.npz"]
    with staged(out, "replace") as stage:
        (stage / "demo-00.npz").write_bytes(b"fresh")
    assert [p.name for p in out.iterdir()] == ["demo-00.npz"] and (out / "demo-00.npz").read_bytes() == b"fresh"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mug"]
    with staged(tmp_path / "new" / "bowl", "replace") as stage:  # a directory that did not exist
        (stage / "demo-00.npz").write_bytes(b"x")
    assert demo_count(tmp_path / "new" / "bowl") == 1


def test_teach_refuses_to_replace_demos_unasked_and_says_how(tmp_path, capsys):
    out = tmp_path / "mug"
    _demos(out, ["demo-00"])
    with pytest.raises(ValueError, match="holds 1 demos: give --replace .* or --add"):
        teach_mode(out, replace=False, add=False)
    assert teach_mode(tmp_path / "empty", replace=False, add=False) == "replace"
    assert main(["teach", "--task", "mug", "--out", str(out), "--demos", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--replace" in err[0]
    assert (out / "demo-00.npz").read_bytes() == b"demo-00"


def test_a_bowl_demo_in_the_mug_folder_is_refused_before_any_template_is_built(tmp_path):
    import shutil

    from app.tasks.demo_library import DEMOS_DIR
    out = tmp_path / "mug"
    out.mkdir()
    for name in ("demo-00.npz", "demo-01.npz"):
        shutil.copy(DEMOS_DIR / "mug" / name, out / name)
    shutil.copy(DEMOS_DIR / "bowl" / "demo-00.npz", out / "demo-02.npz")
    assert main(["teach", "--task", "mug", "--rebuild", "--out", str(out)]) == 2
    assert sorted(p.name for p in out.iterdir()) == ["demo-00.npz", "demo-01.npz", "demo-02.npz"]  # nothing built
    from app.tasks.demo_library import task_templates
    from app.tasks.task import task
    with pytest.raises(ValueError, match="is of task 'bowl', not 'mug'"):
        task_templates(task("mug"), out, rebuild=True)


def test_a_session_killed_between_the_two_renames_loses_nothing(tmp_path):
    """kill -9 inside `swap_in`, after the old folder was set aside and before the new one was put in
    its place: loading says where the demos are, and the next session puts them back."""
    import os

    from app.tasks.demo_library import task_demos
    from app.tasks.staging import leftovers, recover

    out = tmp_path / "mug"
    _demos(out, ["demo-00", "demo-01"])
    os.replace(out, tmp_path / ".mug.old-abc123")  # the first rename
    (tmp_path / ".mug.staging-def456").mkdir()  # the staging folder, never renamed
    with pytest.raises(FileNotFoundError, match=r"interrupted .*\.mug\.old-abc123"):
        task_demos(out)
    recover(out)
    assert (out / "demo-00.npz").read_bytes() == b"demo-00" and leftovers(out) == ([], [])


def test_a_file_where_the_task_folder_goes_is_refused_and_kept(tmp_path):
    (tmp_path / "mug").write_text("my notes")
    with pytest.raises(ValueError, match="is a file"):
        teach_mode(tmp_path / "mug", replace=True, add=False)
    assert (tmp_path / "mug").read_text() == "my notes"
