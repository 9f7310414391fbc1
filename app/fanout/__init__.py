"""Fan-out on Ray: the one way our verbs spread trials, jobs and shards over processes and machines.

`cluster` starts a local Ray (or joins one at `--address` / `RAY_ADDRESS`), `fan_out` runs one task
per item there and yields each outcome as it finishes, `shipping` carries read-only folders to the
nodes through the object store, and `guard` removes Ray's processes when a command is killed.
"""
