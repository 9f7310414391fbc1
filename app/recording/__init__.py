"""Jobs as Rerun recordings (`nift run --rerun`, `nift bench-jobs --rerun`): what a job saw and did on a
timeline of the arm's clock, in one entity layout (docs/recording.md). Imported only when asked for.

layout.py       the entity paths, the gripper's outline and the viewer's blueprint
robot.py        the UR5 and gripper from the cell's URDF, the arm's state as columns, the base frame
job_log.py      `RerunJobLog`: the job's observer (`app.jobs.log.JobLog`) that writes a recording
session_log.py  `SessionRecording`: a teach-in session, step by step
target.py       where a recording goes, checked before the job (no Rerun import)
"""
