#!/usr/bin/env python3
"""A minimal pushlearn world client in Python.

Connects to a running world daemon (``pushlearn-sim``), reads its Hello,
resets the world, puts the actuator on the start line, pushes it forward at
0.5 m/s, reads 150 world states and prints the blue block's final pose.
Works in both timing modes: in lock-step mode it sends an Advance before each
state it waits for.

    python3 examples/python/client.py --host 127.0.0.1 --port 11345

The protocol (docs/protocol.md): every message is a 4-byte big-endian length
followed by that many bytes of one protobuf envelope, ``ClientMessage`` from
client to world and ``ServerMessage`` from world to client.
"""

import argparse
import math
import os
import socket
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pushlearn_pb2 as pb  # noqa: E402  (needs the path above)

MAX_FRAME_SIZE = 16 * 1024 * 1024
STATES = 150


class WorldError(Exception):
    """The world answered with an Error message."""


class Connection:
    """One framed connection; assigns strictly increasing seq numbers."""

    def __init__(self, host, port, timeout):
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.seq = 0

    def close(self):
        self.sock.close()

    def _read_exactly(self, n):
        chunks = []
        while n > 0:
            chunk = self.sock.recv(min(n, 65536))
            if not chunk:
                raise ConnectionError("the world closed the connection")
            chunks.append(chunk)
            n -= len(chunk)
        return b"".join(chunks)

    def read(self):
        """The next ServerMessage."""
        (length,) = struct.unpack(">I", self._read_exactly(4))
        if length > MAX_FRAME_SIZE:
            raise ConnectionError(f"frame of {length} bytes exceeds the 16 MiB limit")
        message = pb.ServerMessage()
        message.ParseFromString(self._read_exactly(length))
        return message

    def send(self, **payload):
        """Sends a ClientMessage with one payload field; returns its seq."""
        self.seq += 1
        data = pb.ClientMessage(seq=self.seq, **payload).SerializeToString()
        self.sock.sendall(struct.pack(">I", len(data)) + data)
        return self.seq

    def next_state(self):
        """The next WorldState; an Error from the world raises WorldError."""
        while True:
            message = self.read()
            kind = message.WhichOneof("payload")
            if kind == "world_state":
                return message.world_state
            if kind == "error":
                error = message.error
                what = pb.Error.Kind.Name(error.kind)
                raise WorldError(f"command {error.seq} ({what}): {error.message}")
            if kind == "hello":
                raise ConnectionError("a second Hello on the same connection")
            # kind is None: a payload added by a newer world; skip it.


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default="127.0.0.1", help="world host (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=11345, help="world port (default 11345)")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds to wait for any message")
    args = parser.parse_args()

    world = None
    try:
        world = Connection(args.host, args.port, args.timeout)
        hello = world.read()
        if hello.WhichOneof("payload") != "hello":
            raise ConnectionError("the world did not start with Hello")
        hello = hello.hello
        # timing_kind is unspecified from worlds older than the field; they
        # say it only in the string.
        if hello.timing_kind != pb.Hello.TIMING_KIND_UNSPECIFIED:
            lockstep = hello.timing_kind == pb.Hello.TIMING_KIND_LOCKSTEP
        else:
            lockstep = hello.timing_mode == "lockstep"
        print(f"scene {hello.scene}, {hello.timing_mode} mode, {hello.publish_rate} Hz, "
              f"bodies: {', '.join(b.name for b in hello.bodies)}")

        world.send(control=pb.SimControl(reset=True))
        start = pb.Pose(position=pb.Vector3d(x=0.0, y=0.0, z=0.03),
                        orientation=pb.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0))
        world.send(set_pose=pb.ModelStateV(models=[pb.ModelState(name="actuator", pose=start)]))
        move_seq = world.send(actuator=pb.ActuatorCommand(
            cmd=pb.ActuatorCommand.MOVE, direction=pb.Vector3d(x=0.0, y=0.5, z=0.0)))

        state = None
        received = 0
        while received < STATES:
            if lockstep:
                world.send(control=pb.SimControl(advance=True))
            state = world.next_state()
            # applied_seq tells whether our commands were in force when the
            # state was produced; earlier states are stale.
            if state.applied_seq >= move_seq:
                received += 1

        blue = next((m for m in state.model_v.models if m.name == "blockA"), None)
        if blue is None:
            raise ConnectionError("the world state has no blockA")
        p, q = blue.pose.position, blue.pose.orientation
        print(f"blockA (blue block) after {STATES} states: x={p.x:.4f} y={p.y:.4f} z={p.z:.4f} "
              f"yaw={yaw_of(q):.4f} (step {state.step}, t={state.sim_time:.3f} s)")
    except (WorldError, OSError) as err:  # OSError covers refused, reset and timed-out sockets
        print(f"error: {err}", file=sys.stderr)
        return 1
    finally:
        if world is not None:
            world.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
