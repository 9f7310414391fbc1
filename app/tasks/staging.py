"""Teach-in writes that lose nothing (our addition): a session records into a staging folder beside
the task's directory, the templates are rebuilt there, and only then does the folder take the
directory's place - holding the new demos alone (`replace`) or the old ones and the new
(`add`). A session that fails or is interrupted leaves the directory as it was, and a staging folder
it leaves behind is a hidden `.NAME.staging-*` sibling that the next session ignores.

The swap is two renames (the old directory aside, the staging folder in), then the old one is
removed: POSIX renames a directory only onto an empty one, so one rename cannot do it. A crash
between the two leaves the old demos complete in `.NAME.old-*` beside it.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from app.io_utils import writable_directory
from app.tasks.demo import DEMO_GLOB

MODES = ("replace", "add")


def demo_count(directory: Path) -> int:
    """How many demo files a task directory holds (0 when it does not exist)."""
    return len(list(Path(directory).glob(DEMO_GLOB))) if Path(directory).is_dir() else 0


def teach_mode(directory: Path, replace: bool, add: bool) -> str:
    """"replace" or "add" as asked; with neither, "replace" for a directory without demos and a
    one-line error for one that has some (nothing is deleted unasked)."""
    if replace and add:
        raise ValueError("give --replace or --add, not both")
    writable_directory(directory, "--out")  # a file there is never swapped for a task folder
    if replace or add:
        return "replace" if replace else "add"
    if n := demo_count(directory):
        raise ValueError(f"{directory} holds {n} demos: give --replace to record new ones in their place "
                         f"or --add to add to them")
    return "replace"


@contextmanager
def staged(out: Path, mode: str) -> Iterator[Path]:
    """A staging folder for a session writing into `out` (with the demos already there for "add");
    on a clean exit it becomes `out`; on an error `out` is untouched and the folder removed."""
    if mode not in MODES:
        raise ValueError(f"unknown teach mode {mode!r}; choose {' or '.join(MODES)}")
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    recover(out)
    stage = Path(tempfile.mkdtemp(prefix=f".{out.name}.staging-", dir=out.parent))
    try:
        if mode == "add" and out.is_dir():
            for demo in sorted(out.glob(DEMO_GLOB)):
                shutil.copy2(demo, stage / demo.name)
        yield stage
        swap_in(stage, out)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def leftovers(out: Path) -> tuple[list[Path], list[Path]]:
    """(staging folders, set-aside old folders) an interrupted session left beside `out`."""
    out = Path(out)
    return (sorted(out.parent.glob(f".{out.name}.staging-*")), sorted(out.parent.glob(f".{out.name}.old-*")))


def recover(out: Path) -> None:
    """Undo what a killed session left (a kill -9 runs no clean-up): its staging folders are removed;
    a set-aside old folder is put back when `out` is missing (killed between the two renames of
    `swap_in`), and removed when `out` is there (killed after them)."""
    staging, old = leftovers(out)
    for folder in staging:
        shutil.rmtree(folder, ignore_errors=True)
    if old and not Path(out).exists():
        os.replace(old[-1], out)
        old = old[:-1]
    for folder in old:
        shutil.rmtree(folder, ignore_errors=True)


def swap_in(stage: Path, out: Path) -> None:
    """Put the staging folder at `out`, the old directory (if any) aside and then removed."""
    if not out.exists():
        os.replace(stage, out)
        return
    old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
    old.rmdir()  # a free name beside out
    os.replace(out, old)
    try:
        os.replace(stage, out)
    except OSError:
        os.replace(old, out)
        raise
    shutil.rmtree(old, ignore_errors=True)
