"""Jobs as Rerun recordings (`nift run --rerun`, `nift bench-jobs --rerun`): what a job saw and did on a
timeline of the arm's clock, in one entity layout (docs/recording.md). Imported only when asked for.

layout.py    the entity paths, the gripper's outline and the viewer's blueprint
robot.py     the UR5 and gripper from the cell's URDF, their joints as columns
job_log.py   `RerunJobLog`: the job's observer (`app.jobs.log.JobLog`) that writes a recording
"""
