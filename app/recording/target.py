"""Where a recording goes, checked before a job starts (no Rerun import): an .rrd file in a folder that
exists and can be written, or None for a viewer to spawn; the files of a series, numbered."""
from __future__ import annotations

import tempfile
from pathlib import Path

SPAWN = "spawn"  # `--rerun` without a path: the viewer


def check_target(value: str | None, flag: str = "--rerun", folder: bool = False) -> Path | None:
    """The recording's path (a folder when `folder`), or None to spawn the viewer; a one-line ValueError
    naming what is wrong."""
    if value is None or value == SPAWN:
        if folder:
            raise ValueError(f"{flag} needs a folder to write the recordings in")
        return None
    path = Path(value)
    where = path if folder else path.parent
    if not folder and path.suffix != ".rrd":
        raise ValueError(f"{flag} {value}: a recording is an .rrd file")
    if not where.is_dir():
        raise ValueError(f"{flag} {value}: no folder {where}")
    try:  # a file made and removed: the mode bits alone do not say it (root, a read-only mount)
        with tempfile.TemporaryFile(dir=where):
            pass
    except OSError as exc:
        raise ValueError(f"{flag} {value}: the folder {where} cannot be written ({exc.strerror})") from None
    if not folder and path.is_dir():
        raise ValueError(f"{flag} {value}: is a folder")
    return path


def open_log(path: Path | None, name: str):
    """A `RerunJobLog` writing to `path` (None: a spawned viewer); Rerun is imported here, not before."""
    from app.recording.job_log import RerunJobLog

    return RerunJobLog(path, name)
