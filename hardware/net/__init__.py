"""The cell's devices as network services (hardware-in-the-loop): a server process exposes an
`Arm`, a `Gripper`, a `DepthCamera` (or any one of them) over ZeroMQ, clients implement the same
interfaces, and python-zeroconf advertises and finds them.

wire.py       the messages: msgpack, numpy arrays as raw bytes, never pickle
checks.py     what a request's arguments must be before they reach a device
verbs.py      which verbs each device kind answers, and how
server.py     `DeviceServer`: CURVE keys, one commanding client, motion under a watchdog
client.py     `NetArm`, `NetGripper`, `NetCamera`
discovery.py  advertising and browsing with zeroconf
keys.py       the CURVE key pairs and the allowed client keys (zmq.auth)
"""
