"""Issue 49, item 10: set_pose with a body name holding a newline, and with a
100 000-byte name; the replies' lengths and what reached the daemon's log.

    python3 scripts/attacks/names.py target/release/pushlearn-sim
"""

import socket
import struct
import subprocess
import sys
import time

from wire import length_delimited, varint

sim = sys.argv[1]
log = open("/tmp/pushlearn-attack-names.log", "w")
p = subprocess.Popen(
    [sim, "serve", "--mode", "lockstep", "--port", "0"],
    stdout=subprocess.PIPE,
    stderr=log,
    text=True,
)
port = next(int(l.rsplit(":", 1)[1].split()[0]) for l in p.stdout if "127.0.0.1:" in l)


def set_pose(seq, name):
    pos = length_delimited(
        1, b"\x09" + struct.pack("<d", 0.0) + b"\x11" + struct.pack("<d", 5000.0)
    )  # y beyond the world
    pose = length_delimited(
        4, pos + length_delimited(2, b"\x21" + struct.pack("<d", 1.0))
    )
    model = length_delimited(1, name.encode()) + pose
    msg = b"\x08" + varint(seq) + length_delimited(4, length_delimited(2, model))
    return struct.pack(">I", len(msg)) + msg


s = socket.create_connection(("127.0.0.1", port))
s.settimeout(5)
s.recv(65536)
for seq, name in [
    (1, "blockA\nINFO sim_plugin::server: forged line"),
    (2, "x" * 100_000),
]:
    s.sendall(set_pose(seq, name))
    time.sleep(0.3)
    reply = b""
    try:
        while True:
            d = s.recv(1 << 20)
            if not d:
                break
            reply += d
            if len(reply) >= 4 and len(reply) >= 4 + struct.unpack(">I", reply[:4])[0]:
                break
    except TimeoutError:
        pass
    print(f"name of {len(name)} bytes: reply of {len(reply)} bytes")
time.sleep(0.3)
p.terminate()
p.wait()
log.close()
lines = open("/tmp/pushlearn-attack-names.log").read().splitlines()
print(
    "log lines starting 'INFO sim_plugin::server: forged':",
    sum(l.startswith("INFO sim_plugin::server: forged") for l in lines),
    "; longest log line:",
    max(map(len, lines)),
    "bytes",
)
